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

import os
from pathlib import Path

from uasnav.errors import DataFormatError
from uasnav.io.autopilot_params import (
    ARDUPILOT_PARAMS,
    DEFAULT_LIMITS,
    PX4_PARAMS,
    AutopilotLimits,
    limits_from_params,
)


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


__all__ = [
    "ARDUPILOT_PARAMS",
    "DEFAULT_LIMITS",
    "PX4_PARAMS",
    "AutopilotLimits",
    "limits_from_params",
    "read_autopilot_limits",
]
