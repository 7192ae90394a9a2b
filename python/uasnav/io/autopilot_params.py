"""The navigation limits an autopilot is configured with (:class:`AutopilotLimits`) and the
parameters they come from; :mod:`uasnav.io.autopilot_limits` reads them from a log (see its
table of parameters and units)."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

#: ArduPilot parameter → (field, factor to SI).
ARDUPILOT_PARAMS: dict[str, tuple[str, float]] = {
    "WPNAV_SPEED": ("cruise_ms", 0.01),
    "WPNAV_ACCEL": ("accel_ms2", 0.01),
    "WPNAV_SPEED_UP": ("climb_ms", 0.01),
    "WPNAV_SPEED_DN": ("descent_ms", 0.01),
    "WPNAV_ACCEL_Z": ("accel_z_ms2", 0.01),
}
#: PX4 parameter → (field, factor to SI); earlier names win (MPC_ACC_HOR before _MAX).
PX4_PARAMS: dict[str, tuple[str, float]] = {
    "MPC_XY_CRUISE": ("cruise_ms", 1.0),
    "MPC_ACC_HOR": ("accel_ms2", 1.0),
    "MPC_ACC_HOR_MAX": ("accel_ms2", 1.0),
    # AUTO climbs and descends at MPC_Z_V_AUTO_UP/DN (PX4 ≥ 1.12); older firmware at _VEL_MAX_
    "MPC_Z_V_AUTO_UP": ("climb_ms", 1.0),
    "MPC_Z_V_AUTO_DN": ("descent_ms", 1.0),
    "MPC_Z_VEL_MAX_UP": ("climb_ms", 1.0),
    "MPC_Z_VEL_MAX_DN": ("descent_ms", 1.0),
    # one vertical limit per model: PX4's up-acceleration, its down one only when that is missing
    "MPC_ACC_UP_MAX": ("accel_z_ms2", 1.0),
    "MPC_ACC_DOWN_MAX": ("accel_z_ms2", 1.0),
}


@dataclass(frozen=True)
class AutopilotLimits:
    """Waypoint-navigation limits of one vehicle (SI; ``None`` = not known).

    Attributes
    ----------
    cruise_ms : float or None
        Horizontal waypoint speed, m/s.
    accel_ms2 : float or None
        Horizontal acceleration limit, m/s².
    climb_ms, descent_ms : float or None
        Vertical speed limits up and down (both > 0), m/s.
    accel_z_ms2 : float or None
        Vertical acceleration limit, m/s².
    source : tuple of str
        Names of the fields that came from a log (the others are defaults or unknown).
    """

    cruise_ms: float | None = None
    accel_ms2: float | None = None
    climb_ms: float | None = None
    descent_ms: float | None = None
    accel_z_ms2: float | None = None
    source: tuple[str, ...] = ()

    def or_defaults(self) -> AutopilotLimits:
        """These limits with every unknown one taken from :data:`DEFAULT_LIMITS`."""
        return replace(
            self,
            **{
                f.name: getattr(DEFAULT_LIMITS, f.name)
                for f in fields(self)
                if f.name != "source" and getattr(self, f.name) is None
            },
        )


#: Limits assumed when a log carries none: the 1 m/s² the kinematic model always used (ArduPilot's
#: WPNAV_ACCEL default of 100 cm/s² before 4.0), ArduPilot's WPNAV_SPEED_UP/DN defaults of 2.5 and
#: 1.5 m/s, its WPNAV_ACCEL_Z default of 1 m/s², and its WPNAV_SPEED default of 5 m/s (a plan's own
#: speed overrides it).
DEFAULT_LIMITS = AutopilotLimits(cruise_ms=5.0, accel_ms2=1.0, climb_ms=2.5, descent_ms=1.5, accel_z_ms2=1.0)


def limits_from_params(values: dict[str, float], table: dict[str, tuple[str, float]]) -> AutopilotLimits:
    out: dict[str, float] = {}
    for name, (field, factor) in table.items():
        v = values.get(name)
        if v is None or field in out:
            continue
        v = float(v) * factor
        if math.isfinite(v) and v > 0:
            out[field] = v
    return AutopilotLimits(**out, source=tuple(sorted(out)))


__all__ = ["ARDUPILOT_PARAMS", "DEFAULT_LIMITS", "PX4_PARAMS", "AutopilotLimits", "limits_from_params"]
