"""Magnetic declination for the GNSS/INS filter's heading aiding.

A magnetometer measures *magnetic* heading; the filter navigates in true north (NED), so its
heading aiding uses ``true = magnetic + declination`` (declination east positive). The
declination comes, in this order, from

1. the configuration (:attr:`uasnav.ins.InsConfig.declination_deg`, or ``uasnav nav
   --declination DEG``);
2. the log, when the autopilot carries a declination it *used*: ArduPilot ``PARM``
   ``COMPASS_DEC`` (radians) when ``COMPASS_AUTODEC`` is 0 (with auto-declination on, the
   autopilot takes its own table's value at run time and the logged parameter is not it);
   PX4 ``EKF2_MAG_DECL`` (degrees) when non-zero;
3. the World Magnetic Model (WMM2010/2015/2020/2025, coefficients shipped by ``pygeomag``)
   at the first GNSS fix and the log's GPS date;
4. otherwise 0 (simulated flights: their magnetometer has none), said as the source.

The WMM's own stated 1σ declination uncertainty is a few tenths of a degree at mid latitudes
(NOAA's error model, ``pygeomag`` ``calculate_uncertainty``); local anomalies and vehicle
iron are not modelled.
"""

from __future__ import annotations

import math
import warnings
from typing import TYPE_CHECKING, Any

from uasnav.errors import InputError

if TYPE_CHECKING:
    from uasnav.io.flight import Flight

__all__ = [
    "resolve_declination",
    "wmm_declination_deg",
    "wmm_model_name",
]

#: Years the shipped WMM coefficients cover (WMM2010 … WMM2025, 5 years each).
WMM_YEARS = (2010.0, 2030.0)


def wmm_declination_deg(lat_deg: float, lon_deg: float, height_m: float, year: float) -> float:
    """Declination (degrees, east positive) of the World Magnetic Model for the model epoch
    that covers ``year`` (decimal year, 2010–2030), at geodetic latitude/longitude (degrees)
    and height above the WGS-84 ellipsoid (m).

    Raises
    ------
    InputError
        Non-finite input, ``|lat| > 90``, or a date the shipped models do not cover (give the
        declination explicitly then).
    """
    vals = (lat_deg, lon_deg, height_m, year)
    if not all(math.isfinite(float(v)) for v in vals) or abs(lat_deg) > 90.0:
        raise InputError(f"declination: bad position/date {vals!r}")
    if not WMM_YEARS[0] <= year < WMM_YEARS[1]:
        raise InputError(
            f"declination: no World Magnetic Model for {year:.2f} (shipped: {WMM_YEARS[0]:.0f}–"
            f"{WMM_YEARS[1]:.0f}); give declination_deg (uasnav nav --declination DEG)"
        )
    res = _geomag(year).calculate(
        glat=float(lat_deg), glon=float(lon_deg), alt=float(height_m) / 1000.0, time=float(year)
    )
    return float(res.d)


def wmm_model_name(year: float) -> str:
    """The WMM release :func:`wmm_declination_deg` uses for ``year`` (e.g. ``"WMM-2015v2"``)."""
    return f"{_geomag(year).model}"


def _geomag(year: float) -> Any:
    from pygeomag import GeoMag

    # pygeomag picks the release covering the year (2015–2019: the out-of-cycle WMM2015v2).
    return GeoMag(base_year=int(year))  # type: ignore[arg-type]


def resolve_declination(flight: Flight, declination_deg: float | None) -> tuple[float, str]:
    """The declination (degrees, east positive) the heading aiding uses, and its source.

    ``declination_deg`` (configuration) wins; then the log's (``flight.meta["declination_deg"]``,
    set by the readers with ``flight.meta["declination_source"]``); then the WMM at the first
    GNSS fix on ``flight.meta["utc_year"]`` (a date outside the shipped models: 0, with a
    warning); else 0 with source ``"none"``.
    """
    if declination_deg is not None:
        d = float(declination_deg)
        if not math.isfinite(d) or abs(d) > 180.0:
            raise InputError(
                f"declination_deg: expected a finite angle in [-180, 180], got {declination_deg!r}"
            )
        return d, "configuration"
    meta: dict[str, Any] = flight.meta
    if meta.get("declination_deg") is not None:
        return float(meta["declination_deg"]), str(meta.get("declination_source", "log"))
    year = meta.get("utc_year")
    if year is not None and not WMM_YEARS[0] <= float(year) < WMM_YEARS[1]:
        # e.g. a receiver with the GPS week-rollover bug (1999 dates), or a log after 2030:
        # the replay goes on without declination, and says so (it is no reason to refuse a log)
        why = (
            f"none (the log is dated {float(year):.2f}, outside the shipped World Magnetic Model "
            f"{WMM_YEARS[0]:.0f}–{WMM_YEARS[1]:.0f}; give declination_deg / uasnav nav --declination)"
        )
        warnings.warn(f"declination: {why}", UserWarning, stacklevel=2)
        return 0.0, why
    if year is not None:
        g = flight.gnss
        lat, lon, alt = float(g.lat[0]), float(g.lon[0]), float(g.alt[0])
        d = wmm_declination_deg(lat, lon, alt, float(year))
        return (
            d,
            f"{wmm_model_name(float(year))} at the first fix ({lat:.4f}°, {lon:.4f}°) on {float(year):.3f}",
        )
    return 0.0, "none (no declination in the log and no date for the magnetic model)"
