"""A photogrammetric survey of a field: boustrophedon lines, camera triggers, flights.

Geometry (nadir camera, flat ground, the image's wide side across the track):

* Height for a ground sample distance g (m/px) with a camera of horizontal field of view α
  over w pixels: h = g·w / (2·tan(α/2)) (eq. 60 solved for the height). The flight height is
  the lowest of that height, the operator's ``--altitude`` and the legal maximum; the survey
  says which one won (:attr:`SurveyPlan.height_reason`). The GSD at the flown height is then
  g' = 2·h·tan(α/2)/w ≤ g.
* Footprint: across track W = 2·h·tan(α/2), along track L = W·(h_px/w_px) (square pixels).
* Line spacing S = W·(1 − side overlap), trigger distance D = L·(1 − front overlap). Lines
  are laid across the field's smallest width (the direction of a convex-hull edge that gives
  the fewest lines, hence the fewest turns) and centred so that the swaths W + (n − 1)·S
  cover the field; along a line, photos are taken every D from one footprint-centre before
  the field edge to one after, so the first and last footprints reach past the edges.
* Speed along the lines: at most D / (shortest trigger interval) — the camera must be ready
  for the next photo — and at most b·g'/t_e, motion blur of ``b`` pixels at exposure t_e,
  and at most the UAS's cruise speed.
* Each line is flown with a run-in before its first photo and a run-out after its last
  (v²/2a, at least :data:`MIN_RUN_M`): the vehicle is at speed and on the line while
  photographing. Triggers are MAVLink ``DO_SET_CAM_TRIGG_DIST`` (distance D and "trigger
  once now" at the line's start, distance 0 at its end).
* Endurance: the lines are flown in order, alternating direction, split into flights whose
  estimated time (each leg rest to rest, L/v + v/a, plus climb and descent) stays within the
  UAS's endurance less the reserve; a flight resumes at the photo where the previous stopped.

Heights are metres above the take-off point, which the survey takes as the ground of a flat
field (stated in :attr:`SurveyPlan.assumptions`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from uasnav.errors import InputError
from uasnav.io.mission_plan import (
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_RETURN_TO_LAUNCH,
    MAV_CMD_NAV_TAKEOFF,
    MAV_CMD_NAV_WAYPOINT,
    HomePosition,
    MissionItem,
    MissionPlan,
)

#: MAVLink ``MAV_CMD_DO_SET_CAM_TRIGG_DIST``: param1 distance (m, 0 stops), param3 trigger once now.
MAV_CMD_DO_SET_CAM_TRIGG_DIST = 206
#: Shortest run-in / run-out at a line end, m.
MIN_RUN_M = 5.0
#: Default front and side overlaps (photogrammetric mapping of fields).
DEFAULT_OVERLAP = (0.75, 0.65)
#: Exposure assumed when the camera database gives none, s (1/1000 s: daylight mapping).
DEFAULT_EXPOSURE_S = 1.0 / 1000.0
#: Shortest interval between two photos assumed when the database gives none, s (mapping and
#: multispectral cameras store one capture per second or faster).
DEFAULT_TRIGGER_INTERVAL_S = 1.0
#: Motion blur accepted during the exposure, pixels.
DEFAULT_BLUR_PX = 0.5
#: Horizontal acceleration assumed for turnarounds and the flight-time estimate, m/s²
#: (ArduPilot ``WPNAV_ACCEL`` default 2.5 m/s² is the limit; 1 m/s² is conservative).
DEFAULT_ACCEL_MS2 = 1.0
#: Vertical speeds for the time estimate, m/s (ArduPilot WPNAV_SPEED_UP / _DN defaults).
CLIMB_MS, DESCENT_MS = 2.5, 1.5
#: Most photos a survey may plan (bounds memory and time on absurd requests).
MAX_PHOTOS = 200_000


@dataclass(frozen=True)
class Camera:
    """The camera of a survey: horizontal field of view (deg), image width and height (px), and
    its exposure and shortest trigger interval (s) with where they came from."""

    name: str
    hfov_deg: float
    width_px: float
    height_px: float
    exposure_s: float = DEFAULT_EXPOSURE_S
    trigger_interval_s: float = DEFAULT_TRIGGER_INTERVAL_S
    timing_source: str = "stated defaults (exposure 1/1000 s, one photo per second)"

    def __post_init__(self) -> None:
        for name in ("hfov_deg", "width_px", "height_px", "exposure_s", "trigger_interval_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise InputError(f"camera {self.name}: {name} must be finite and > 0, got {v!r}")
        if self.hfov_deg >= 180:
            raise InputError(f"camera {self.name}: hfov_deg must be < 180, got {self.hfov_deg!r}")

    @classmethod
    def from_table(cls, cameras, j: int) -> Camera:
        """Camera ``j`` of a :class:`~uasnav.mission.database.CameraTable` (the database gives
        no exposure or trigger interval: the stated defaults apply)."""
        return cls(
            name=cameras.label(j),
            hfov_deg=float(cameras.hfov_deg[j]),
            width_px=float(cameras.resolution_w_px[j]),
            height_px=float(cameras.resolution_h_px[j]),
        )

    def height_for(self, gsd_m: float) -> float:
        """Height (m) at which one pixel covers ``gsd_m`` on the ground."""
        return gsd_m * self.width_px / (2.0 * math.tan(math.radians(self.hfov_deg) / 2.0))

    def footprint(self, height_m: float) -> tuple[float, float]:
        """(across, along) footprint on flat ground at ``height_m``, m."""
        w = 2.0 * height_m * math.tan(math.radians(self.hfov_deg) / 2.0)
        return w, w * self.height_px / self.width_px


@dataclass(frozen=True)
class Line:
    """One survey line in the local east/north frame (m): first and last photo positions and
    the run-in/run-out ends; ``photos`` positions along it."""

    start_en: tuple[float, float]
    end_en: tuple[float, float]
    run_in_en: tuple[float, float]
    run_out_en: tuple[float, float]
    photos: int

    @property
    def length_m(self) -> float:
        return float(math.dist(self.start_en, self.end_en))


@dataclass
class SurveyPlan:
    """A planned survey (see module). Distances m, heights m above take-off, speeds m/s."""

    altitude_m: float
    height_reason: str
    gsd_m: float
    footprint_m: tuple[float, float]
    spacing_m: float
    trigger_m: float
    speed_ms: float
    speed_reason: str
    heading_deg: float
    lines: list[Line]
    #: Per flight: the lines (or parts of lines) it flies, in order.
    flights: list[list[Line]]
    origin: tuple[float, float]  # (lat, lon) of the local frame: the take-off point
    overlap: tuple[float, float]
    camera: Camera
    assumptions: list[str] = field(default_factory=list)
    estimated_time_s: list[float] = field(default_factory=list)
    endurance_s: float = math.inf

    @property
    def photos(self) -> int:
        return sum(ln.photos for f in self.flights for ln in f)

    @property
    def length_m(self) -> float:
        """Photographed length of the lines, m."""
        return float(sum(ln.length_m for ln in self.lines))

    def photo_positions(self, flight: int | None = None) -> np.ndarray:
        """Trigger points, shape (k, 2), east/north m: every D from each line's start."""
        out = []
        for k, f in enumerate(self.flights):
            if flight is not None and k != flight:
                continue
            for ln in f:
                a, b = np.asarray(ln.start_en), np.asarray(ln.end_en)
                t = np.arange(ln.photos) * self.trigger_m
                u = (b - a) / max(np.linalg.norm(b - a), 1e-12)
                out.append(a[None, :] + t[:, None] * u[None, :])
        return np.vstack(out) if out else np.zeros((0, 2))


def _rot(theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


def _best_heading(poly, spacing_m: float) -> float:
    """Direction (rad, from east counter-clockwise) of the lines: the convex-hull edge
    direction across which the field is narrowest (fewest lines, fewest turns)."""
    hull = np.asarray(poly.convex_hull.exterior.coords)
    best, best_w = 0.0, math.inf
    for a, b in itertools.pairwise(hull):
        d = b - a
        if np.hypot(*d) < 1e-6:
            continue
        th = math.atan2(d[1], d[0])
        y = (hull @ _rot(-th).T)[:, 1]
        w = float(y.max() - y.min())
        # ties (a rectangle's two long sides) to the lowest angle: reproducible
        if w < best_w - 1e-6:
            best, best_w = th, w
    return best


def plan_survey(
    field_en,
    camera: Camera,
    *,
    resolution_m: float,
    origin: tuple[float, float],
    takeoff_en: tuple[float, float] = (0.0, 0.0),
    altitude_m: float | None = None,
    legal_max_m: float = 120.0,
    overlap: tuple[float, float] = DEFAULT_OVERLAP,
    cruise_ms: float = 10.0,
    endurance_s: float = math.inf,
    blur_px: float = DEFAULT_BLUR_PX,
    accel_ms2: float = DEFAULT_ACCEL_MS2,
) -> SurveyPlan:
    """Plan the survey of ``field_en`` (a shapely polygon in the local east/north frame about
    ``origin``, m) with ``camera`` at ``resolution_m`` (m/px); see the module.

    ``endurance_s`` is the flight time available per flight (endurance less the reserve).

    Raises
    ------
    InputError
        Overlaps outside [0, 0.95], a non-positive resolution, a field with no area, a height
        below 1 m, or more than :data:`MAX_PHOTOS` photos.
    """
    front, side = overlap
    if not (0.0 <= front <= 0.95 and 0.0 <= side <= 0.95):
        raise InputError(f"overlap {front:g},{side:g}: each must be in [0, 0.95]")
    if not (math.isfinite(resolution_m) and resolution_m > 0):
        raise InputError(f"resolution {resolution_m!r} m/px: must be finite and > 0")
    if field_en.is_empty or field_en.area <= 0:
        raise InputError("the survey area has no surface: give a polygon")
    h_res = camera.height_for(resolution_m)
    cands = [(h_res, f"resolution: {resolution_m:g} m/px with {camera.name} is reached at {h_res:.1f} m")]
    if altitude_m is not None:
        cands.append((altitude_m, f"operator: --altitude {altitude_m:g} m is below {h_res:.1f} m"))
    cands.append((legal_max_m, f"legal maximum: {legal_max_m:g} m above ground"))
    h, reason = min(cands, key=lambda c: c[0])
    if h < 1.0:
        raise InputError(
            f"survey height {h:.2f} m ({reason}): below 1 m above ground — no camera survey flies that low"
        )
    gsd = 2.0 * h * math.tan(math.radians(camera.hfov_deg) / 2.0) / camera.width_px
    w, length = camera.footprint(h)
    spacing = w * (1.0 - side)
    trig = length * (1.0 - front)
    limits = [
        (
            trig / camera.trigger_interval_s,
            f"trigger interval {camera.trigger_interval_s:g} s every {trig:.1f} m",
        ),
        (
            blur_px * gsd / camera.exposure_s,
            f"motion blur {blur_px:g} px at exposure {camera.exposure_s:g} s and {gsd * 100:.2f} cm/px",
        ),
        (cruise_ms, "the UAS's cruise speed"),
    ]
    v, v_reason = min(limits, key=lambda c: c[0])
    heading = _best_heading(field_en, spacing)
    rot_in = _rot(-heading)  # world → line frame (lines along +x)
    ring = np.asarray(field_en.exterior.coords) @ rot_in.T
    y0, y1 = float(ring[:, 1].min()), float(ring[:, 1].max())
    extent = y1 - y0
    n_lines = 1 if extent <= w else math.ceil((extent - w) / spacing - 1e-9) + 1
    from shapely import affinity
    from shapely import geometry as sg

    local = affinity.rotate(field_en, -heading, origin=(0, 0), use_radians=True)
    ys = (y0 + y1) / 2 + (np.arange(n_lines) - (n_lines - 1) / 2) * spacing
    run = max(MIN_RUN_M, v * v / (2 * accel_ms2))
    rot_out = _rot(heading)
    lines: list[Line] = []
    total = 0
    x_lo, x_hi = float(ring[:, 0].min()) - 1.0, float(ring[:, 0].max()) + 1.0
    for k, y in enumerate(ys):
        band = local.intersection(sg.box(x_lo, y - w / 2, x_hi, y + w / 2))
        if band.is_empty:
            continue
        bx0, _, bx1, _ = band.bounds
        n_ph = max(2, math.ceil((bx1 - bx0) / trig - 1e-9) + 2)
        span = (n_ph - 1) * trig
        xa = (bx0 + bx1) / 2 - span / 2
        xb = xa + span
        total += n_ph
        if total > MAX_PHOTOS:
            raise InputError(
                f"the survey needs more than {MAX_PHOTOS} photos: a smaller area or a coarser resolution"
            )
        pts = np.array([[xa - run, y], [xa, y], [xb, y], [xb + run, y]])
        if k % 2 == 1:
            pts = pts[::-1]
        wpts = pts @ rot_out.T
        lines.append(Line(tuple(wpts[1]), tuple(wpts[2]), tuple(wpts[0]), tuple(wpts[3]), n_ph))
    assumptions = [
        "flat terrain: heights are above the take-off point, taken as the ground of the whole field",
        f"camera timing: {camera.timing_source}",
    ]
    sp = SurveyPlan(
        altitude_m=h,
        height_reason=reason,
        gsd_m=gsd,
        footprint_m=(w, length),
        spacing_m=spacing,
        trigger_m=trig,
        speed_ms=v,
        speed_reason=v_reason,
        heading_deg=(90.0 - math.degrees(heading)) % 180.0,
        lines=lines,
        flights=[],
        origin=origin,
        overlap=(front, side),
        camera=camera,
        assumptions=assumptions,
        endurance_s=endurance_s,
    )
    _split_flights(sp, takeoff_en, accel_ms2)
    return sp


def _leg_time(a, b, v: float, accel: float) -> float:
    """A leg from rest to rest at v with acceleration ``accel``: L/v + v/a (or 2√(L/a))."""
    d = math.dist(a, b)
    if d <= 0:
        return 0.0
    if d < v * v / accel:
        return 2.0 * math.sqrt(d / accel)
    return d / v + v / accel


def _estimate(sp: SurveyPlan, takeoff, lines: list[Line], accel: float) -> float:
    """Conservative flight time (s) of a flight over ``lines`` from and back to ``takeoff``."""
    h = sp.altitude_m
    t = h / CLIMB_MS + CLIMB_MS / 1.0 + h / DESCENT_MS + DESCENT_MS / 1.0
    pos = takeoff
    for ln in lines:
        for p in (ln.run_in_en, ln.start_en, ln.end_en, ln.run_out_en):
            t += _leg_time(pos, p, sp.speed_ms, accel)
            pos = p
    return t + _leg_time(pos, takeoff, sp.speed_ms, accel)


def _cut(sp: SurveyPlan, ln: Line, keep: int) -> tuple[Line, Line]:
    """``ln`` split after its ``keep``-th photo: (first part, rest resuming at the next photo)."""
    a, b = np.asarray(ln.start_en), np.asarray(ln.end_en)
    u = (b - a) / max(float(np.linalg.norm(b - a)), 1e-12)
    run = float(np.linalg.norm(np.asarray(ln.start_en) - np.asarray(ln.run_in_en)))
    end1 = a + (keep - 1) * sp.trigger_m * u
    start2 = a + keep * sp.trigger_m * u
    first = Line(tuple(a), tuple(end1), ln.run_in_en, tuple(end1 + run * u), keep)
    rest = Line(tuple(start2), tuple(b), tuple(start2 - run * u), ln.run_out_en, ln.photos - keep)
    return first, rest


def _split_flights(sp: SurveyPlan, takeoff, accel: float) -> None:
    avail = sp.endurance_s
    flights: list[list[Line]] = []
    cur: list[Line] = []
    queue = list(sp.lines)
    while queue:
        ln = queue.pop(0)
        if _estimate(sp, takeoff, [*cur, ln], accel) <= avail:
            cur.append(ln)
            continue
        # the most photos of this line that still fit (at least 2 per part)
        lo, hi, best = 2, ln.photos - 1, 0
        while lo <= hi:
            mid = (lo + hi) // 2
            if _estimate(sp, takeoff, [*cur, _cut(sp, ln, mid)[0]], accel) <= avail:
                best, lo = mid, mid + 1
            else:
                hi = mid - 1
        if best >= 2 and ln.photos - best >= 1:
            first, rest = _cut(sp, ln, best)
            cur.append(first)
            queue.insert(0, rest)
        elif not cur:
            raise InputError(
                f"one flight of the survey needs more than the {avail:.0f} s available per flight "
                f"even for two photos of a line: the field is too far from the take-off point for this UAS"
            )
        else:
            queue.insert(0, ln)
        flights.append(cur)
        cur = []
    if cur:
        flights.append(cur)
    sp.flights = flights
    sp.estimated_time_s = [_estimate(sp, takeoff, f, accel) for f in flights]


def flight_plan(sp: SurveyPlan, k: int, *, home_amsl_m: float, name: str = "survey") -> MissionPlan:
    """The mission plan of flight ``k`` (0-based): take-off to the survey height, the speed,
    for each line run-in → first photo (start the distance trigger) → last photo (stop it) →
    run-out, then return to launch. Altitudes relative to home (the take-off point)."""
    from uasnav.geo import frames

    lat0, lon0 = sp.origin
    h = sp.altitude_m

    def wp(en) -> MissionItem:
        la, lo, _ = frames.enu_to_geodetic(en[0], en[1], 0.0, lat0, lon0, 0.0)
        return MissionItem(MAV_CMD_NAV_WAYPOINT, 3, (0.0, 0.0, 0.0, math.nan), float(la), float(lo), h)

    items = [
        MissionItem(MAV_CMD_NAV_TAKEOFF, 3, (0.0, 0.0, 0.0, math.nan), lat0, lon0, h),
        MissionItem(MAV_CMD_DO_CHANGE_SPEED, 2, (1.0, sp.speed_ms, -1.0, 0.0)),
    ]
    for ln in sp.flights[k]:
        items += [
            wp(ln.run_in_en),
            wp(ln.start_en),
            MissionItem(MAV_CMD_DO_SET_CAM_TRIGG_DIST, 2, (sp.trigger_m, 0.0, 1.0, 0.0)),
            wp(ln.end_en),
            MissionItem(MAV_CMD_DO_SET_CAM_TRIGG_DIST, 2, (0.0, 0.0, 0.0, 0.0)),
            wp(ln.run_out_en),
        ]
    items.append(
        MissionItem(MAV_CMD_NAV_RETURN_TO_LAUNCH, 2, (0.0, 0.0, 0.0, 0.0), math.nan, math.nan, math.nan)
    )
    return MissionPlan(
        items=tuple(items),
        home=HomePosition(lat0, lon0, home_amsl_m),
        cruise_speed_ms=sp.speed_ms,
        hover_speed_ms=sp.speed_ms,
        source=f"{name} flight {k + 1}",
        vehicle_type=2,
    )


__all__ = [
    "DEFAULT_OVERLAP",
    "MAV_CMD_DO_SET_CAM_TRIGG_DIST",
    "Camera",
    "Line",
    "SurveyPlan",
    "flight_plan",
    "plan_survey",
]
