"""Quaternion attitude and free-inertial drift (thesis §4.2.5.3, eq. 35, Tables 7–8).

The thesis' Tables 7–8 grow linearly in time, i.e. each column is a constant residual rate
|ω| = θ/t. We infer |ω| from the largest threshold of each column and recompute every crossing
time with the propagator: agreement with the other rows checks both the tool and the reading of
the tables.

>>> from uasnav.experiments.attitude import table_check
>>> from uasnav.experiments.thesis import TABLE7
>>> r = table_check(7)
>>> round(r.w_nn_rad_s, 7), round(r.t_nn_s[-1], 2), TABLE7[1.75e-2][0]
(0.0005952, 29.4, 29.4)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from uasnav.attitude import DriftResult, crossing_table, drift
from uasnav.errors import InputError
from uasnav.experiments.thesis import TABLE7, TABLE8

#: Integration step (s) and length (s) of the drift runs: 40 s covers the thesis' longest time.
DT_S = 0.01
DURATION_S = 40.0

_TABLES = {7: ("Δω_MAX", TABLE7), 8: ("Δω_RMS", TABLE8)}


@dataclass(frozen=True)
class TableCheck:
    """One of the thesis' Tables 7–8 recomputed from the residual rates it implies.

    Attributes
    ----------
    table : int
        Thesis table number (7 or 8).
    residual : str
        Which residual the table is for (``"Δω_MAX"`` or ``"Δω_RMS"``).
    w_nn_rad_s, w_pf_rad_s : float
        Residual rate |ω| (rad/s) implied by the largest threshold of the BPNN (NN) and the
        polynomial (PF) column.
    drift_nn, drift_pf : DriftResult
        θ(t) of the two residual rates (rad), 40 s at 100 Hz.
    thresholds_rad : tuple of float
        Attitude thresholds θ (rad), ascending.
    t_nn_s, t_pf_s : tuple of (float or None)
        Our crossing times (s) per threshold.
    dt_percent : tuple of (float or None)
        Our Δt% (eq. 36) per threshold (%).
    thesis_t_nn_s, thesis_t_pf_s : tuple of float
        The thesis' crossing times (s) per threshold.
    thesis_dt_percent : tuple of float
        Eq. 36 applied to the thesis' printed times (%); differs from the printed Δt% column
        (kept in :mod:`uasnav.experiments.thesis`) by the rounding of those times.
    """

    table: int
    residual: str
    w_nn_rad_s: float
    w_pf_rad_s: float
    drift_nn: DriftResult
    drift_pf: DriftResult
    thresholds_rad: tuple[float, ...]
    t_nn_s: tuple[float | None, ...]
    t_pf_s: tuple[float | None, ...]
    dt_percent: tuple[float | None, ...]
    thesis_t_nn_s: tuple[float, ...]
    thesis_t_pf_s: tuple[float, ...]
    thesis_dt_percent: tuple[float, ...]


def table_check(table: int) -> TableCheck:
    """Recompute thesis Table ``table`` (7 or 8) with the attitude propagator."""
    if table not in _TABLES:
        raise InputError(f"table: expected 7 or 8, got {table!r}")
    residual, ref = _TABLES[table]
    th_max = max(ref)
    w_nn = th_max / ref[th_max][0]
    w_pf = th_max / ref[th_max][1]
    # Split the residual over the three axes: θ depends only on |ω| for a constant rate.
    u = np.array([1.0, -1.0, 1.0]) / np.sqrt(3.0)
    d_nn = drift(w_nn * u, DT_S, duration=DURATION_S)
    d_pf = drift(w_pf * u, DT_S, duration=DURATION_S)
    rows = crossing_table(d_nn, d_pf)
    thesis_nn = tuple(ref[th][0] for th, *_ in rows)
    thesis_pf = tuple(ref[th][1] for th, *_ in rows)
    return TableCheck(
        table=table,
        residual=residual,
        w_nn_rad_s=w_nn,
        w_pf_rad_s=w_pf,
        drift_nn=d_nn,
        drift_pf=d_pf,
        thresholds_rad=tuple(r[0] for r in rows),
        t_nn_s=tuple(r[1] for r in rows),
        t_pf_s=tuple(r[2] for r in rows),
        dt_percent=tuple(r[3] for r in rows),
        thesis_t_nn_s=thesis_nn,
        thesis_t_pf_s=thesis_pf,
        thesis_dt_percent=tuple((a - b) / b * 100 for a, b in zip(thesis_nn, thesis_pf, strict=True)),
    )


@dataclass(frozen=True)
class AttitudeResult:
    """Tables 7 and 8 recomputed (see :class:`TableCheck`)."""

    table7: TableCheck
    table8: TableCheck


def run(
    *, seed: int = 2024, quick: bool = False, progress: Callable[[str], None] | None = None
) -> AttitudeResult:
    """Recompute the thesis' Tables 7–8.

    Deterministic and fast: ``seed`` and ``quick`` are accepted for the common experiment
    signature and not used; ``progress`` receives nothing.
    """
    return AttitudeResult(table7=table_check(7), table8=table_check(8))


__all__ = ["DT_S", "DURATION_S", "AttitudeResult", "TableCheck", "run", "table_check"]
