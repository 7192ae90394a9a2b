"""Height datums: every height uasnav reads or compares says what it is measured from.

========================= ==================================================================
:class:`HeightDatum`      the height is measured …
========================= ==================================================================
``ELLIPSOID``             above the WGS-84 ellipsoid (GNSS ``alt_ellipsoid``, ECEF-derived)
``AMSL``                  above mean sea level as the *source* models it: a GNSS receiver's
                          AMSL is its ellipsoidal height minus its own geoid model (often a
                          coarse EGM96 table), an autopilot's AMSL is its receiver's
``ABOVE_HOME``            above the home / EKF origin point (relative altitude)
``ABOVE_GROUND``          above the terrain under the vehicle
``UNKNOWN``               not stated by the source (e.g. a barometer's pressure altitude)
========================= ==================================================================

Converting AMSL → ellipsoid needs the geoid undulation N (``h = H + N``). A receiver that
reports both heights gives its own N (:func:`receiver_undulation`), which is exactly the N its
AMSL used; :mod:`uasnav.geo.geoid` gives EGM96 where only one height is known.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.errors import InputError


class HeightDatum(str, enum.Enum):
    """What a height is measured from (the value is the name used in JSON and tables)."""

    ELLIPSOID = "ellipsoid"
    AMSL = "amsl"
    ABOVE_HOME = "above_home"
    ABOVE_GROUND = "above_ground"
    UNKNOWN = "unknown"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class Height:
    """A height (m, scalar or array) with its datum; ``geoid`` names the geoid model behind an
    AMSL height when known (e.g. ``"receiver"``, ``"EGM96"``)."""

    value: float | NDArray[np.float64]
    datum: HeightDatum
    geoid: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.datum, HeightDatum):
            raise InputError(f"Height.datum: expected a HeightDatum, got {self.datum!r}")


def receiver_undulation(alt_ellipsoid_m: ArrayLike, alt_amsl_m: ArrayLike) -> float:
    """The geoid undulation N (m) a GNSS receiver used: the median of ``alt_ellipsoid − alt_amsl``
    over the fixes where both are finite.

    Raises
    ------
    InputError
        If no fix carries both heights, or the result is not a plausible undulation (|N| > 150 m:
        the geoid stays within −107…+86 m of the ellipsoid).

    Examples
    --------
    >>> receiver_undulation([100.0, 101.0, 102.0], [54.5, 55.5, 56.5])
    45.5
    """
    h = np.asarray(alt_ellipsoid_m, dtype=np.float64)
    big_h = np.asarray(alt_amsl_m, dtype=np.float64)
    if h.shape != big_h.shape:
        raise InputError(f"receiver_undulation: shapes differ ({h.shape} vs {big_h.shape})")
    d = (h - big_h)[np.isfinite(h) & np.isfinite(big_h)]
    if d.size == 0:
        raise InputError("receiver_undulation: no fix has both an ellipsoidal and an AMSL height")
    n = float(np.median(d))
    if not abs(n) <= 150.0:
        raise InputError(f"receiver_undulation: {n:.1f} m is not a geoid undulation (|N| ≤ 150 m)")
    return n


__all__ = ["Height", "HeightDatum", "receiver_undulation"]
