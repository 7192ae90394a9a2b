"""The vehicle's configured navigation limits, read from the parameters a flight log carries.

ArduPilot logs its parameters (``PARAM_VALUE`` in a MAVLink ``.tlog``, ``PARM`` in a DataFlash
``.bin``), in cm/s and cm/s²; PX4 stores them in the ULog header (``initial_parameters``), in
m/s and m/s². The waypoint-navigation limits mapped here:

============  ===========================  ================================
limit         ArduPilot (cm/s, cm/s²)      PX4 (m/s, m/s²)
============  ===========================  ================================
cruise        ``WPNAV_SPEED``              ``MPC_XY_CRUISE``
horiz. accel  ``WPNAV_ACCEL``              ``MPC_ACC_HOR`` (else ``MPC_ACC_HOR_MAX``)
climb         ``WPNAV_SPEED_UP``           ``MPC_Z_VEL_MAX_UP``
descent       ``WPNAV_SPEED_DN``           ``MPC_Z_VEL_MAX_DN``
vert. accel   ``WPNAV_ACCEL_Z``            ``MPC_ACC_UP_MAX`` (else ``MPC_ACC_DOWN_MAX``)
============  ===========================  ================================

A limit the log does not carry (or carries as a non-finite or non-positive value) is ``None``;
:meth:`AutopilotLimits.or_defaults` fills it from :data:`DEFAULT_LIMITS` and records which
fields came from the log, so a prediction can say what it assumed.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, fields, replace
from pathlib import Path

from uasnav.errors import DataFormatError

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


def _limits(values: dict[str, float], table: dict[str, tuple[str, float]]) -> AutopilotLimits:
    out: dict[str, float] = {}
    for name, (field, factor) in table.items():
        v = values.get(name)
        if v is None or field in out:
            continue
        v = float(v) * factor
        if math.isfinite(v) and v > 0:
            out[field] = v
    return AutopilotLimits(**out, source=tuple(sorted(out)))


def read_autopilot_limits(path: str | os.PathLike[str]) -> AutopilotLimits:
    """The navigation limits configured in a flight log (``.tlog``, ``.bin``, ``.ulg``).

    Parameters
    ----------
    path : path-like
        The log.

    Returns
    -------
    AutopilotLimits
        Limits in SI units; ``None`` for those the log does not carry (see the module table).

    Raises
    ------
    DataFormatError
        Unreadable log or a format that carries no parameters.

    Examples
    --------
    >>> read_autopilot_limits("mission.csv")
    Traceback (most recent call last):
    ...
    uasnav.errors.DataFormatError: mission.csv: no autopilot parameters in a '.csv' file (.tlog .bin .ulg)
    """
    from uasnav.io.logfile import open_log

    p = Path(path)
    ext = p.suffix.lower()
    if ext in (".tlog", ".bin", ".ulg"):
        return open_log(p, need=("limits",)).limits  # type: ignore[no-any-return]
    raise DataFormatError(f"no autopilot parameters in a {ext!r} file (.tlog .bin .ulg)", path=str(p))


__all__ = ["DEFAULT_LIMITS", "AutopilotLimits", "read_autopilot_limits"]
