"""Plan files as the horizontal route the predictor takes: a thin face of :mod:`uasnav.io.plans`.

Kept for the callers that want ``(route north/east m, origin)`` in one call. Any plan format
is read by its extension (QGroundControl ``.plan``, ``.waypoints``, plan ``.csv``); a file with
another extension is read as a plan CSV, as before the other formats existed.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from uasnav.io.plan_formats.csv_plan import read_plan_csv
from uasnav.io.plans import MAX_PLAN_BYTES, PLAN_READERS, plan_route
from uasnav.io.plans import read_plan as read_mission_plan


def read_plan(path: str | Path) -> tuple[np.ndarray, tuple[float, float, float] | None]:
    """Read a plan file. Returns (waypoints north/east m, geodetic origin or None).

    The route is :func:`uasnav.io.plans.plan_route` of the plan: waypoints in flown order, the
    origin the first waypoint (lat °, lon °, alt m), None for a ``north,east`` CSV. At most
    :data:`MAX_PLAN_BYTES` are read; errors name the file and the line or JSON path.
    """
    p = Path(path)
    plan = read_mission_plan(p) if p.suffix.lower() in PLAN_READERS else read_plan_csv(p)
    return plan_route(plan)


__all__ = ["MAX_PLAN_BYTES", "read_plan"]
