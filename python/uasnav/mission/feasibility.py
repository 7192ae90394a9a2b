"""Feasibility tests of §5.2.3.4 (Figures 71–73), vectorised over the database.

Each test gives a boolean mask plus the value and the limit it was compared with, so that a
rejection can say which test failed and by how much.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from uasnav.errors import InputError
from uasnav.mission.database import CameraTable, UasTable

#: Heights the cameras can be tested at (:attr:`Requirements.camera_height`).
CAMERA_HEIGHTS = ("planned", "regulatory-max")
#: Lowest height a survey is planned at, m above ground (clear of trees, buildings and people's
#: heads on an agricultural field; below it a camera is too narrow for the resolution asked).
MIN_SURVEY_HEIGHT_M = 10.0
#: UA types that can fly the planned survey's lines: stop at a line's end, turn on the spot and
#: go on along the next line one swath (tens of metres) away, take off and land vertically.
HOVERING_TYPES = frozenset({"multirotor", "helicopter"})
#: Bank angle of a fixed wing's survey turn, deg: comfortable for a survey, below the
#: autopilots' roll limits (ArduPlane ``ROLL_LIMIT_DEG`` 45°, PX4 ``FW_R_LIM`` 50°).
SURVEY_BANK_DEG = 30.0
_G = 9.80665


@dataclass(frozen=True)
class Requirements:
    """Mission requirements and weather (thesis Table 22; defaults are that case).

    Parameters
    ----------
    mission : str
        Mission id of Table 18 (e.g. ``"precision-agriculture"``).
    range_m : float
        Largest distance from the take-off point (m).
    resolution_m : float
        Required ground resolution (m/px).
    image_size_m : (float, float)
        Size of the target on the ground, length × width (m); the length sets the HFOV.
    altitude_m : float
        Required flight altitude above ground (m).
    imagery : str or None
        Camera type required (rgb, multispectral, thermal …); None accepts any.
    wind_ms : float
        Wind speed (m/s).
    rain : bool
        Whether the flight must be possible in rain (UAS needs IPX3 or a rain rating).
    speed_ms : float or None
        Required ground speed against the wind (m/s); None: no requirement.
    jurisdiction : str
        Regulations applied (``easa``, ``faa``).
    category : str or None
        Category (``open``/``specific``, ``part107``); None: derived from the operation
        (:func:`uasnav.mission.operation.derive_operation`).
    cruise_fraction : float
        Cruise airspeed as a fraction of the maximum speed, for the endurance test.
    reserve : float
        Fraction of the endurance kept in reserve.
    max_distance_m : float or None
        Largest distance between remote pilot and UA (m); None: ``range_m``.
    vlos_distance_m : float or None
        Distance up to which the UA is kept in sight (m); None: the default of
        :mod:`uasnav.mission.operation`.
    over_people : {"none", "uninvolved", "assemblies"}
    population_density : float or None
        Population density of the operational area (ppl/km²).
    population_class : str or None
        A SORA 2.5 population class name instead of a number (``remote``, ``lightly`` …).
    night : bool
    airspace : str
        ``uncontrolled``, ``controlled``, ``tmz``, ``airport-bcd``, ``airport-efg``, ``atypical``.
    gnss_autopilot : bool
        A GNSS-based autopilot is required (thesis Table 22 "GNSS autopilot: Yes").
    mitigations : tuple of (str, str)
        SORA mitigations claimed, (name, robustness) (2.5: M1A M1B M1C M2; 2.0: M1 M2 M3).
    sora_edition : {"2.5", "2.0"}
    ground_elevation_m : float or None
        Ground elevation above mean sea level (m), to compare AMSL zone limits.
    observers : int
        Airspace observers along the route (EVLOS).
    residual_arc : {"a", "b", "c", "d"} or None
        Residual ARC claimed after strategic air-risk mitigations (SORA step #5); None: the
        initial ARC (:func:`uasnav.mission.sora.residual_arc_of` checks the claim).
    flight_duration_s : float or None
        Flight duration (s) for the zones' schedules (take-off + duration); None: the chosen
        UAS's mission time estimate (:func:`mission_time_s`).
    camera_height : {"planned", "regulatory-max"}
        Height at which the cameras' field of view and resolution are tested: the planned flight
        height ``altitude_m`` (what the operator will get), or the highest height the category
        allows (the thesis' rule, §5.2.3.4).
    mosaic : bool
        The target is covered by many photos (a survey, ``uasnav plan``): no single photo has to
        hold it (no field-of-view test), and the resolution only has to be reachable at or above
        :data:`MIN_SURVEY_HEIGHT_M` (the survey flies at the height that gives it). The survey's
        lines are a rotorcraft pattern, so only :data:`HOVERING_TYPES` fly it (test
        ``survey-pattern``).
    """

    mission: str = "precision-agriculture"
    range_m: float = 1500.0
    resolution_m: float = 0.05
    image_size_m: tuple[float, float] = (70.0, 70.0)
    altitude_m: float = 50.0
    imagery: str | None = "multispectral"
    wind_ms: float = 5.0
    rain: bool = False
    speed_ms: float | None = None
    jurisdiction: str = "easa"
    category: str | None = None
    cruise_fraction: float = 0.7
    reserve: float = 0.2
    max_distance_m: float | None = None
    vlos_distance_m: float | None = None
    over_people: str = "none"
    population_density: float | None = None
    population_class: str | None = None
    night: bool = False
    airspace: str = "uncontrolled"
    gnss_autopilot: bool = True
    mitigations: tuple[tuple[str, str], ...] = ()
    sora_edition: str = "2.5"
    ground_elevation_m: float | None = None
    observers: int = 0
    residual_arc: str | None = None
    flight_duration_s: float | None = None
    #: Where ``altitude_m`` came from when not ``--altitude`` (a plan flying higher), else None.
    altitude_source: str | None = None
    #: Where ``max_distance_m`` was measured when not ``--max-distance`` (the area or the planned
    #: route, from the pilot's position), else None.
    max_distance_source: str | None = None
    camera_height: str = "planned"
    mosaic: bool = False

    def __post_init__(self) -> None:
        checks = {
            "range_m": (self.range_m, 0.0),
            "resolution_m": (self.resolution_m, 0.0),
            "altitude_m": (self.altitude_m, 0.0),
            "image_size_m[0]": (self.image_size_m[0], 0.0),
            "image_size_m[1]": (self.image_size_m[1], 0.0),
        }
        for name, (v, lo) in checks.items():
            if not math.isfinite(v) or v <= lo:
                raise InputError(f"requirement {name}={v}: must be finite and > {lo}")
        if not math.isfinite(self.wind_ms) or self.wind_ms < 0:
            raise InputError(f"requirement wind_ms={self.wind_ms}: must be finite and >= 0")
        if self.speed_ms is not None and (not math.isfinite(self.speed_ms) or self.speed_ms < 0):
            raise InputError(f"requirement speed_ms={self.speed_ms}: must be finite and >= 0")
        if not 0.0 < self.cruise_fraction <= 1.0:
            raise InputError(f"cruise_fraction={self.cruise_fraction}: must be in (0, 1]")
        for name in ("max_distance_m", "vlos_distance_m"):
            v = getattr(self, name)
            if v is not None and (not math.isfinite(v) or v <= 0):
                raise InputError(f"requirement {name}={v}: must be finite and > 0")
        if self.population_density is not None and (
            not math.isfinite(self.population_density) or self.population_density < 0
        ):
            raise InputError(
                f"requirement population_density={self.population_density}: must be finite and >= 0"
            )
        if self.ground_elevation_m is not None and not math.isfinite(self.ground_elevation_m):
            raise InputError(f"requirement ground_elevation_m={self.ground_elevation_m}: must be finite")
        if not 0 <= self.observers <= 100:
            raise InputError(f"requirement observers={self.observers}: must be in 0..100")
        if self.camera_height not in CAMERA_HEIGHTS:
            raise InputError(
                f"camera_height={self.camera_height!r}: expected one of {', '.join(CAMERA_HEIGHTS)}"
            )
        if not 0.0 <= self.reserve < 1.0:
            raise InputError(f"reserve={self.reserve}: must be in [0, 1)")


@dataclass(frozen=True)
class TestResult:
    """One test over n items: ``ok`` mask, compared ``value`` and ``limit`` arrays, unit."""

    name: str
    ok: np.ndarray
    value: np.ndarray
    limit: np.ndarray
    unit: str
    relation: str  # how value must relate to limit: ">", ">=", "<=", "=="


@dataclass(frozen=True)
class Rejection:
    """Why one UAS, camera or pair was rejected."""

    kind: str  # "uas" | "camera" | "pair" | "mission"
    item: str
    test: str
    value: float
    limit: float
    unit: str
    message: str


def required_hfov_deg(length_m: float, height_m: float) -> float:
    """HFOV needed to cover a target of length L from height h: α = 2·atan(L/2h) (eq. 60), deg."""
    if length_m <= 0 or height_m <= 0:
        raise InputError(f"required_hfov_deg: L={length_m} m and h={height_m} m must be > 0")
    return math.degrees(2.0 * math.atan(length_m / (2.0 * height_m)))


def ground_resolution_m(hfov_deg: np.ndarray, pixels: np.ndarray, height_m: float) -> np.ndarray:
    """Ground sample distance (m/px) at nadir: footprint 2·h·tan(HFOV/2) over the pixels across."""
    return 2.0 * height_m * np.tan(np.radians(hfov_deg) / 2.0) / pixels


def mission_time_s(range_m: float, airspeed_ms: np.ndarray, wind_ms: float) -> np.ndarray:
    """Time (s) to fly out and back over ``range_m`` with the wind against one leg.

    t = R/(V − W) + R/(V + W), the worst wind direction for a straight out-and-back leg; inf
    where the airspeed does not exceed the wind (Figure 71: no progress upwind).
    """
    v = np.asarray(airspeed_ms, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = range_m / (v - wind_ms) + range_m / (v + wind_ms)
    return np.where(v > wind_ms, t, np.inf)


def uas_tests(u: UasTable, req: Requirements, max_mtom_g: float) -> list[TestResult]:
    """Tests on the aircraft alone, in the thesis' order (wind, endurance, altitude, speed)."""
    n = len(u)
    full = np.full(n, 1.0)
    out = [
        TestResult("wind", u.max_speed_ms > req.wind_ms, u.max_speed_ms, full * req.wind_ms, "m/s", ">"),
    ]
    t_req = mission_time_s(req.range_m, req.cruise_fraction * u.max_speed_ms, req.wind_ms)
    t_avail = u.endurance_min * 60.0 * (1.0 - req.reserve)
    out.append(TestResult("endurance", t_req <= t_avail, t_avail, t_req, "s", ">="))
    # the C2 link must reach the UA where it flies farthest from the pilot (--max-distance),
    # not only the mission range
    link_m = req.range_m if req.max_distance_m is None else max(req.range_m, req.max_distance_m)
    out.append(TestResult("link-range", u.max_range_m >= link_m, u.max_range_m, full * link_m, "m", ">="))
    out.append(
        TestResult(
            "altitude", u.max_altitude_m >= req.altitude_m, u.max_altitude_m, full * req.altitude_m, "m", ">="
        )
    )
    if req.speed_ms is not None:
        rel = u.max_speed_ms - req.wind_ms
        out.append(TestResult("speed", rel >= req.speed_ms, rel, full * req.speed_ms, "m/s", ">="))
    out.append(TestResult("regulation-mass", u.mass_g < max_mtom_g, u.mass_g, full * max_mtom_g, "g", "<"))
    if req.rain:
        out.append(TestResult("rain", u.rain.copy(), u.rain.astype(float), full, "rated", "=="))
    if req.mosaic:
        # A UA that cannot hover turns on a circle of radius v²/(g·tan φ) at its cruise speed:
        # the value says how wide, against the 0 m of a stop-and-turn at the line's end.
        hover = np.array([t in HOVERING_TYPES for t in u.types], dtype=bool)
        v = req.cruise_fraction * u.max_speed_ms
        across = np.where(hover, 0.0, 2.0 * v**2 / (_G * math.tan(math.radians(SURVEY_BANK_DEG))))
        out.append(TestResult("survey-pattern", hover, across, full * 0.0, "m", "<="))
    return out


def equipment_tests(u: UasTable, gnss_autopilot: bool, need: list[tuple[str, str]]) -> list[TestResult]:
    """Equipment the UAS must carry: ``gnss-autopilot`` when ``gnss_autopilot``, and each
    (database token, item name) of ``need``. A UAS without an equipment record fails (what the
    database does not record cannot be claimed). The test's ``unit`` holds the item name."""
    n = len(u)
    full = np.full(n, 1.0)
    items = ([("gnss-autopilot", "GNSS-based autopilot (thesis Table 22)")] if gnss_autopilot else []) + [
        t for t in need if t[0] != "gnss-autopilot"
    ]
    out = []
    seen = set()
    for token, name in items:
        if token in seen:
            continue
        seen.add(token)
        ok = u.has(token)
        out.append(TestResult("equipment:" + token, ok, ok.astype(float), full, name, "=="))
    return out


def camera_tests(c: CameraTable, req: Requirements, height_m: float) -> list[TestResult]:
    """Camera tests: imagery type, HFOV (eq. 60) and ground resolution at ``height_m``.

    ``height_m`` is the planned height or the maximum height the regulations allow (thesis
    §5.2.3.4), as :attr:`Requirements.camera_height` says. For a survey (``req.mosaic``) there
    is no field-of-view test and the resolution is tested at :data:`MIN_SURVEY_HEIGHT_M`: the
    survey flies at the height that gives it, as long as that height is not lower.
    """
    n = len(c)
    full = np.full(n, 1.0)
    out = []
    if req.imagery is not None:
        ok = np.array([t == req.imagery for t in c.types], dtype=bool)
        out.append(TestResult("imagery", ok, ok.astype(float), full, req.imagery, "=="))
    if req.mosaic:
        gsd = ground_resolution_m(c.hfov_deg, c.resolution_w_px, MIN_SURVEY_HEIGHT_M)
        out.append(
            TestResult("resolution", gsd <= req.resolution_m, gsd, full * req.resolution_m, "m/px", "<=")
        )
        return out
    alpha = required_hfov_deg(req.image_size_m[0], height_m)
    out.append(TestResult("hfov", c.hfov_deg >= alpha, c.hfov_deg, full * alpha, "deg", ">="))
    gsd = ground_resolution_m(c.hfov_deg, c.resolution_w_px, height_m)
    out.append(TestResult("resolution", gsd <= req.resolution_m, gsd, full * req.resolution_m, "m/px", "<="))
    return out


def pair_tests(u: UasTable, c: CameraTable, max_mtom_g: float) -> list[TestResult]:
    """Tests on each UAS × camera pair: payload capacity, published MTOM, regulatory mass."""
    cam = c.mass_g[None, :]
    mass = u.mass_g[:, None] + cam
    payload = np.broadcast_to(u.payload_g[:, None], mass.shape)
    mtom = np.where(np.isnan(u.max_takeoff_g), np.inf, u.max_takeoff_g)[:, None]
    return [
        TestResult("payload", payload >= cam, payload, np.broadcast_to(cam, mass.shape), "g", ">="),
        TestResult("max-takeoff", mass <= mtom, np.broadcast_to(mtom, mass.shape), mass, "g", ">="),
        TestResult("regulation-mass", mass < max_mtom_g, mass, np.full(mass.shape, max_mtom_g), "g", "<"),
    ]


def describe(test: TestResult, i, label: str) -> str:
    """One-line reason: what failed and by how much."""
    v, lim = float(test.value[i]), float(test.limit[i])
    if test.name == "imagery":
        return f"{label}: imagery is not {test.unit}"
    if test.name.startswith("equipment:"):
        token = test.name.removeprefix("equipment:")
        return (
            f"{label}: lacks {test.unit}, necessary for this operation (no '{token}' in its equipment record)"
        )
    if test.name == "vlos-distance":
        return (
            f"{label}: kept in sight only up to {v:.0f} m (its size, EASA AMC1 Art. 11 Annex A "
            f"§A.5.2.5), the pilot-UA distance is {lim:g} m"
        )
    if test.name == "rain":
        return f"{label}: not rated for rain (needs IPX3 or better)"
    if test.name == "survey-pattern":
        return (
            f"{label}: survey-pattern: cannot hover, and a {SURVEY_BANK_DEG:g}°-bank turn at its cruise "
            f"speed is {v:.0f} m across; the survey is planned for rotorcraft, which stop at each line's "
            "end and turn onto the next line one swath away (fixed-wing survey patterns are not planned)"
        )
    if test.name == "endurance":
        if not math.isfinite(lim):
            return f"{label}: endurance: cruise airspeed does not exceed the wind"
        return (
            f"{label}: endurance: needs {lim:.0f} s, has {v:.0f} s after reserve (short by {lim - v:.0f} s)"
        )
    return (
        f"{label}: {test.name}: {v:.4g} {test.unit} not {test.relation} {lim:.4g} {test.unit} "
        f"(by {abs(lim - v):.3g} {test.unit})"
    )
