"""Trajectory prediction for the web application: an uploaded plan in, times and a drawing out.

The page (``POST /trajectory``) and the API (``POST /api/trajectory/predict``) both call
:func:`read_uploaded_plan` and :func:`predict_plan`; the CSV and GeoJSON downloads are
:func:`waypoints_csv` and :func:`waypoints_geojson` of the same result.

Uploads are written only inside a fresh temporary directory, under a fixed name chosen here
(never the client's file name), and read back with the package's hardened readers.
"""

from __future__ import annotations

import csv
import io
import json
import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from uasnav.errors import DataFormatError, InputError, UasnavError
from uasnav.io.mission_plan import MissionPlan
from uasnav.io.plans import MAX_PLAN_BYTES, PLAN_EXTENSIONS, plan_cruise_speed, plan_route, read_plan
from uasnav.trajectory.autopilot import (
    FAMILIES,
    mission_params,
    plan_family,
    predict_mission,
    qgc_mission_time,
)
from uasnav.trajectory.features import wind_vector
from uasnav.trajectory.models import Predictor, load_model, method_of
from uasnav.trajectory.predictor import MAX_MODEL_BYTES, Feasibility

#: Plan formats accepted, by file-name suffix (the readers of :mod:`uasnav.io.plans`):
#: QGroundControl ``.plan``, Mission Planner ``.waypoints``/``.txt``, uasnav's ``.csv``.
PLAN_SUFFIXES = PLAN_EXTENSIONS
#: Plan formats an autopilot flies as a mission (take-off, speed changes, holds, landing):
#: these get the autopilot's mission execution model as ``uasnav trajectory mission`` runs it;
#: a CSV is a route of waypoints only, for the element model.
MISSION_SUFFIXES = tuple(s for s in PLAN_SUFFIXES if s != ".csv")
#: Autopilot families of the mission model (``uasnav trajectory mission --autopilot``).
AUTOPILOTS = FAMILIES
#: What the page calls each family.
AUTOPILOT_LABELS = {
    "arducopter": "ArduCopter (multirotor)",
    "px4-mc": "PX4 multicopter",
    "plane": "ArduPlane / QuadPlane (fixed wing, VTOL)",
}
#: The parameter of each family's horizontal mission speed (:attr:`MissionParams.cruise_ms`).
CRUISE_PARAM = {"arducopter": "WPNAV_SPEED", "px4-mc": "MPC_XY_CRUISE", "plane": "AIRSPEED_CRUISE"}
#: MAVLink ``MAV_CMD`` names of the items a mission table shows (MAVLink common.xml).
MAV_CMD_NAMES = {
    16: "waypoint",
    17: "loiter (unlimited)",
    18: "loiter turns",
    19: "loiter time",
    20: "return to launch",
    21: "land",
    22: "take-off",
    31: "loiter to altitude",
    82: "spline waypoint",
    84: "VTOL take-off",
    85: "VTOL land",
    93: "delay",
    177: "jump",
    178: "change speed",
}
#: Largest uploaded plan and model (bytes).
MAX_UPLOAD_PLAN_BYTES = min(MAX_PLAN_BYTES, 4 * 2**20)
MAX_UPLOAD_MODEL_BYTES = min(MAX_MODEL_BYTES, 8 * 2**20)
#: Largest wind (m/s) accepted: the CLI's --wind bound.
MAX_WIND_MS = 100.0
#: Largest commanded speed (m/s) accepted.
MAX_SPEED_MS = 150.0


class FieldError(InputError):
    """A bad value of one form field or API key; ``field`` names it."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field


def _suffix(filename: str) -> str:
    return Path(filename.replace("\\", "/")).suffix.lower()


def _write_upload(tmp: Path, stem: str, suffix: str, data: bytes) -> Path:
    # fixed name inside our own temporary directory: nothing of the request reaches a path
    p = tmp / f"{stem}{suffix}"
    p.write_bytes(data)
    return p


@dataclass(frozen=True)
class UploadedPlan:
    """An uploaded plan's horizontal route (north/east m, shape (n, 2)), geodetic origin (lat
    deg, lon deg, alt m; None for a local plan) and commanded cruise speed (m/s, if given);
    ``mission`` is the plan itself for an autopilot mission file (:data:`MISSION_SUFFIXES`),
    None for a route (CSV)."""

    route_ne: np.ndarray
    origin: tuple[float, float, float] | None
    cruise_ms: float | None
    mission: MissionPlan | None = None


def read_uploaded_plan(filename: str, data: bytes) -> UploadedPlan:
    """Parse an uploaded plan with :func:`uasnav.io.plans.read_plan` (format by suffix).

    Raises
    ------
    FieldError
        ``field == "plan"``: empty, too large, unknown type, or malformed (the reader's message,
        with line and column, without the temporary path).
    """
    suffix = _suffix(filename or "")
    if suffix not in PLAN_SUFFIXES:
        raise FieldError(
            "plan", f"plan: unsupported file type {suffix or '(none)'!r}; expected {', '.join(PLAN_SUFFIXES)}"
        )
    if not data:
        raise FieldError("plan", "plan: the file is empty")
    if len(data) > MAX_UPLOAD_PLAN_BYTES:
        raise FieldError("plan", f"plan: file over {MAX_UPLOAD_PLAN_BYTES} bytes")
    if b"\x00" in data:
        raise FieldError("plan", "plan: binary data, not a text plan")
    with tempfile.TemporaryDirectory(prefix="uasnav-plan-") as tmp:
        path = _write_upload(Path(tmp), "plan", suffix, data)
        try:
            plan = read_plan(path)
            route, origin = plan_route(plan)
        except UasnavError as e:
            raise FieldError("plan", "plan: " + str(e).replace(str(path), filename or "plan")) from None
    if route.shape[0] < 2:
        raise FieldError("plan", "plan: needs at least two positioned waypoints")
    from uasnav.web.server_limits import check_plan_work

    try:
        check_plan_work(route.shape[0])
    except InputError as e:
        raise FieldError("plan", f"plan: {e}") from None
    return UploadedPlan(
        np.asarray(route, dtype=float)[:, :2],
        origin,
        plan_cruise_speed(plan),
        plan if suffix in MISSION_SUFFIXES else None,
    )


@dataclass(frozen=True)
class AutopilotPrediction:
    """The mission as the autopilot flies it (:func:`uasnav.trajectory.autopilot.predict_mission`
    with the firmware defaults), the numbers of ``uasnav trajectory mission --json``.

    ``chosen_by`` says where the family came from: ``"plan"`` (the CLI's default rule,
    :func:`uasnav.trajectory.autopilot.plan_family`) or ``"form"``.
    """

    autopilot: str
    firmware: str | None
    eta_s: float
    landed: bool
    qgc_estimate_s: float
    items: list[dict[str, Any]]
    parameters: dict[str, dict[str, Any]]
    #: The horizontal mission speed the model flies (m/s) and its parameter's name.
    cruise_ms: float
    cruise_param: str
    chosen_by: str = "plan"

    @property
    def label(self) -> str:
        return AUTOPILOT_LABELS.get(self.autopilot, self.autopilot)

    def to_dict(self) -> dict[str, Any]:
        """The keys of ``uasnav trajectory mission --json``, plus ``chosen_by``."""
        return {
            "autopilot": self.autopilot,
            "firmware": self.firmware,
            "eta_s": self.eta_s,
            "landed": self.landed,
            "qgc_estimate_s": self.qgc_estimate_s,
            "items": [{k: r[k] for k in ("item", "command", "arrive_s")} for r in self.items],
            "parameters": self.parameters,
            "chosen_by": self.chosen_by,
        }


def predict_autopilot(plan: MissionPlan, autopilot: str | None = None) -> AutopilotPrediction:
    """When each item of ``plan`` is reached and the mission ends, as ``uasnav trajectory
    mission PLAN [--autopilot …]`` computes it (the same functions, firmware defaults, home
    altitude unknown), beside QGroundControl's own estimate.

    Raises
    ------
    FieldError
        ``field == "autopilot"`` for an unknown family; ``"plan"`` when the model refuses the plan.
    """
    if autopilot is not None and autopilot not in AUTOPILOTS:
        raise FieldError("autopilot", f"autopilot: {autopilot!r} is not one of {', '.join(AUTOPILOTS)}")
    family = autopilot or plan_family(plan)
    try:
        params = mission_params(family, None, {})
        pred = predict_mission(plan, params, home_amsl_m=None)
        qgc = qgc_mission_time(plan, params.cruise_ms, None)
    except UasnavError as e:
        raise FieldError("plan", f"plan: {e}") from None
    items = [
        {
            "item": int(i),
            "command": int(c),
            "name": MAV_CMD_NAMES.get(int(c), f"MAV_CMD {int(c)}"),
            "arrive_s": float(t),
        }
        for i, c, t in zip(pred.items, pred.commands, pred.arrive_s, strict=True)
    ]
    return AutopilotPrediction(
        autopilot=family,
        firmware=params.version,
        eta_s=float(pred.eta_s),
        landed=bool(pred.landed),
        qgc_estimate_s=float(qgc),
        items=items,
        parameters={k: {"value": params.values[k], "source": params.sources[k]} for k in params.values},
        cruise_ms=float(params.cruise_ms),
        cruise_param=CRUISE_PARAM.get(family, "cruise speed"),
        chosen_by="plan" if autopilot is None else "form",
    )


def read_uploaded_model(data: bytes) -> Predictor:
    """Parse an uploaded model JSON with the package's checked loader (``field == "model"``)."""
    if len(data) > MAX_UPLOAD_MODEL_BYTES:
        raise FieldError("model", f"model: file over {MAX_UPLOAD_MODEL_BYTES} bytes")
    with tempfile.TemporaryDirectory(prefix="uasnav-model-") as tmp:
        path = _write_upload(Path(tmp), "model", ".json", data)
        try:
            return load_model(path)  # either method (kinematic default, LVQ)
        except UasnavError as e:
            raise FieldError("model", "model: " + str(e).replace(str(path), "model")) from None


def parse_number(field_name: str, value: Any, lo: float, hi: float, *, lo_open: bool = False) -> float:
    """A finite number within [lo, hi] (``(lo, hi]`` with ``lo_open``) or a :class:`FieldError`."""
    try:
        if isinstance(value, bool):
            raise ValueError
        x = float(value.strip() if isinstance(value, str) else value)
    except (TypeError, ValueError):
        raise FieldError(field_name, f"{field_name}: {value!r} is not a number") from None
    if not math.isfinite(x) or x > hi or (x <= lo if lo_open else x < lo):
        op = ">" if lo_open else ">="
        raise FieldError(field_name, f"{field_name}: {value} is not {op} {lo:g} and <= {hi:g}")
    return x


@dataclass
class RoutePrediction:
    """What the trajectory page shows and the API answers (units in the key names)."""

    eta_s: float
    waypoints: list[dict[str, Any]]
    elements: list[dict[str, Any]]
    origin: tuple[float, float, float] | None
    wind: dict[str, float]
    speed_ms: float
    model: str
    notes: list[str] = field(default_factory=list)
    #: The model's method ("kinematic" default, "lvq" the thesis' network), as the CLI's ``method``.
    method: str = ""
    #: 4D plan check (required time per waypoint within a tolerance), if asked for.
    feasibility: Feasibility | None = None
    #: For an autopilot mission file: the mission as the autopilot flies it (the page's ETA).
    autopilot: AutopilotPrediction | None = None

    def to_dict(self) -> dict[str, Any]:
        extra: dict[str, Any] = {}
        if self.feasibility is not None:
            # the keys of `uasnav trajectory predict --required … --json`
            extra = {
                "feasible": self.feasibility.feasible,
                "waypoint_ok": [bool(x) for x in self.feasibility.ok],
                "tolerance_s": self.feasibility.tolerance_s,
            }
        return extra | {
            "eta_s": self.eta_s,
            "waypoint_times_s": [w["time_s"] for w in self.waypoints],
            "waypoints": self.waypoints,
            "elements": self.elements,
            "origin": None if self.origin is None else list(self.origin),
            "wind": self.wind,
            "speed_ms": self.speed_ms,
            "model": self.model,
            "method": self.method,
            "low_confidence_elements": [e["element"] for e in self.elements if e["low_confidence"]],
            "autopilot": None if self.autopilot is None else self.autopilot.to_dict(),
        }


def parse_required(text: str, n_waypoints: int) -> np.ndarray:
    """``"0,15,30"`` → the required time (s from the start) of each of ``n_waypoints``."""
    try:
        vals = np.array([float(x) for x in text.split(",") if x.strip()])
    except ValueError:
        raise FieldError("required", f"required: expected comma-separated times in s, got {text!r}") from None
    if vals.shape != (n_waypoints,) or not np.isfinite(vals).all():
        raise FieldError(
            "required", f"required: need one finite time per waypoint ({n_waypoints}), got {vals.size}"
        )
    return vals


def predict_plan(
    model: Predictor,
    plan_ne: np.ndarray,
    origin: tuple[float, float, float] | None,
    wind_speed_ms: float,
    wind_from_deg: float,
    speed_ms: float | None,
    model_name: str,
    required_s: np.ndarray | None = None,
    tolerance_s: float = 5.0,
) -> RoutePrediction:
    """Element times (eq. 47), ETA and 4D waypoint times of a plan, as plain rows; with
    ``required_s``, each waypoint's time checked within ``tolerance_s`` (the CLI's rule,
    :class:`~uasnav.trajectory.predictor.Feasibility`)."""
    p = model.predict(plan_ne, wind_vector(wind_speed_ms, wind_from_deg), speed_ms)
    feas = None
    if required_s is not None:
        feas = Feasibility(np.asarray(required_s, dtype=float), p.waypoint_times_s, float(tolerance_s))
    el = p.elements
    latlon = None
    if origin is not None:
        from uasnav.geo import frames

        lat, lon, _ = frames.ned_to_geodetic(plan_ne[:, 0], plan_ne[:, 1], 0.0, *origin)
        latlon = np.column_stack([lat, lon])
    waypoints = []
    for i, t in enumerate(p.waypoint_times_s):
        w: dict[str, Any] = {
            "waypoint": i,
            "north_m": float(plan_ne[i, 0]),
            "east_m": float(plan_ne[i, 1]),
            "time_s": float(t),
        }
        if latlon is not None:
            w["lat_deg"] = float(latlon[i, 0])
            w["lon_deg"] = float(latlon[i, 1])
        if feas is not None:
            w["required_s"] = float(feas.required_s[i])
            w["ok"] = bool(feas.ok[i])
        waypoints.append(w)
    # the predictor's own rows (as `uasnav trajectory predict --json`), plus what the page draws
    starts = np.concatenate([[0.0], np.cumsum(p.time_s)[:-1]]) if len(p.time_s) else np.zeros(0)
    elements = [
        {
            **row,
            "start_time_s": float(starts[i]),
            "path_ne_m": [
                [float(el.start_ne[i, 0]), float(el.start_ne[i, 1])],
                [float(el.mid_ne[i, 0]), float(el.mid_ne[i, 1])],
                [float(el.end_ne[i, 0]), float(el.end_ne[i, 1])],
            ],
        }
        for i, row in enumerate(p.element_rows())
    ]
    return RoutePrediction(
        eta_s=float(p.eta_s),
        waypoints=waypoints,
        elements=elements,
        origin=origin,
        wind={"speed_ms": wind_speed_ms, "from_deg": wind_from_deg},
        speed_ms=float(model.cruise_ms_ if speed_ms is None else speed_ms),
        model=model_name,
        feasibility=feas,
        method=method_of(model),
    )


def waypoints_csv(r: RoutePrediction) -> str:
    """The 4D waypoint times as CSV: waypoint, north_m, east_m[, lat_deg, lon_deg], time_s."""
    cols = ["waypoint", "north_m", "east_m"] + (["lat_deg", "lon_deg"] if r.origin else []) + ["time_s"]
    if r.feasibility is not None:
        cols += ["required_s", "ok"]
    out = io.StringIO()
    w = csv.DictWriter(out, cols, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for row in r.waypoints:
        w.writerow(
            {
                k: (f"{v:.8f}" if k.endswith("_deg") else f"{v:.3f}" if isinstance(v, float) else v)
                for k, v in row.items()
            }
        )
    return out.getvalue()


def mission_items_csv(a: AutopilotPrediction) -> str:
    """The mission items as the autopilot flies them, as CSV: item, command, name, arrive_s
    (the rows of ``uasnav trajectory mission --json`` ``items``, with the command's name)."""
    out = io.StringIO()
    w = csv.DictWriter(out, ["item", "command", "name", "arrive_s"], lineterminator="\n")
    w.writeheader()
    for row in a.items:
        w.writerow({**row, "arrive_s": f"{row['arrive_s']:.3f}"})
    return out.getvalue()


def waypoints_geojson(r: RoutePrediction) -> dict[str, Any]:
    """The 4D waypoints as a GeoJSON FeatureCollection (RFC 7946: lon, lat), with ``time_s``.

    Raises
    ------
    InputError
        For a plan in local north/east metres (no geodetic origin).
    """
    if r.origin is None:
        raise FieldError("format", "format: GeoJSON needs a plan in lat/lon (this one is in north/east m)")
    feats = [
        {
            "type": "Feature",
            "geometry": {"type": "Point", "coordinates": [w["lon_deg"], w["lat_deg"]]},
            "properties": {"waypoint": w["waypoint"], "time_s": w["time_s"]},
        }
        for w in r.waypoints
    ]
    feats.append(
        {
            "type": "Feature",
            "geometry": {
                "type": "LineString",
                "coordinates": [[w["lon_deg"], w["lat_deg"]] for w in r.waypoints],
            },
            "properties": {"eta_s": r.eta_s},
        }
    )
    return {"type": "FeatureCollection", "features": feats}


def route_drawing(
    r: RoutePrediction, width: float = 640.0, pad: float = 28.0, *, with_times: bool = True
) -> dict[str, Any]:
    """Screen coordinates of the route drawn to scale (east right, north up) in an SVG box;
    each waypoint labelled with its number and, ``with_times``, its element-model time.

    Returns the view box size, each element's polyline and flag, the waypoints and a scale bar
    of a round length (1, 2 or 5 × 10ⁿ m).
    """
    pts = np.array([[w["east_m"], w["north_m"]] for w in r.waypoints])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = np.maximum(hi - lo, 1.0)
    k = (width - 2 * pad) / max(span[0], span[1])
    height = span[1] * k + 2 * pad
    width_used = span[0] * k + 2 * pad

    def xy(east: float, north: float) -> tuple[float, float]:
        return (round(pad + (east - lo[0]) * k, 2), round(height - pad - (north - lo[1]) * k, 2))

    elements = []
    for e in r.elements:
        poly = " ".join("{:.2f},{:.2f}".format(*xy(pe, pn)) for pn, pe in e["path_ne_m"])
        elements.append(
            {"points": poly, "low": e["low_confidence"], "element": e["element"], "time_s": e["time_s"]}
        )
    # one label per drawn point: a closed route's first and last waypoints share theirs
    labels: dict[tuple[float, float], list[str]] = {}
    for w in r.waypoints:
        text = f"{w['waypoint']} · {w['time_s']:.1f} s" if with_times else str(w["waypoint"])
        labels.setdefault(xy(w["east_m"], w["north_m"]), []).append(text)
    box_width = max(width_used, 160.0)
    wps = [
        # labels right of the point, or left of it near the right edge of the drawn box (not
        # of the nominal width: a tall route is drawn narrower) so none is cut off
        {"x": x, "y": y, "label": " / ".join(texts), "anchor": "end" if x > 0.6 * box_width else "start"}
        for (x, y), texts in labels.items()
    ]
    target = max(span) / 4
    mag = 10 ** math.floor(math.log10(target))
    bar_m = max(m * mag for m in (1, 2, 5) if m * mag <= target) if target >= mag else mag
    return {
        "width": round(box_width, 2),
        "height": round(height, 2),
        "elements": elements,
        "waypoints": wps,
        "scale_m": bar_m,
        "scale_px": round(bar_m * k, 2),
    }


def to_json_text(obj: Any) -> str:
    """Compact JSON, non-finite numbers as null (same rule as every uasnav JSON)."""
    from uasnav.jsonable import to_jsonable

    return json.dumps(to_jsonable(obj), ensure_ascii=False)


__all__ = [
    "AUTOPILOTS",
    "MAX_UPLOAD_MODEL_BYTES",
    "MAX_UPLOAD_PLAN_BYTES",
    "MISSION_SUFFIXES",
    "PLAN_SUFFIXES",
    "AutopilotPrediction",
    "DataFormatError",
    "FieldError",
    "RoutePrediction",
    "UploadedPlan",
    "mission_items_csv",
    "parse_number",
    "parse_required",
    "predict_autopilot",
    "predict_plan",
    "read_uploaded_model",
    "read_uploaded_plan",
    "route_drawing",
    "waypoints_csv",
    "waypoints_geojson",
]
