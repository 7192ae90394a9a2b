"""uasnav — navigation and mission management for small unmanned aircraft.

Public modules (one concept each):

- :mod:`uasnav.allan` — overlapping Allan deviation and IMU noise identification
- :mod:`uasnav.attitude` — quaternion attitude propagation and free-inertial drift
- :mod:`uasnav.imu` — the in-memory IMU recording type; :mod:`uasnav.io` reads and writes logs
- :mod:`uasnav.units` — named unit conversions (deg/√h ↔ rad/√s, g ↔ m/s², …)
- :mod:`uasnav.errors` — the exception hierarchy

Conventions: SI units, NED local-level navigation frame, body frame x forward / y right /
z down, quaternions scalar first (Hamilton) rotating body → NED.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("uasnav")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    from uasnav._core import __version__


def plan(options=None, /, **kw):  # type: ignore[no-untyped-def]
    """Plan the survey of a field and everything its authorisation needs: the same structure
    as ``uasnav plan --json`` (:func:`uasnav.mission.planner.plan`; its ``result`` is
    ``result.json``, its ``files`` every file the command writes)."""
    from uasnav.mission.planner import plan as _plan

    return _plan(options, **kw)


__all__ = ["__version__", "plan"]
