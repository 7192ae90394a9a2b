"""Fleet-relative anomaly score of IMU health rows: robust z-scores within each IMU model.

For each metric m and IMU model group G (``imu_model``: the same sensor part across the fleet),

    z = 0.6745 (x − median_G) / MAD_G,     MAD_G = median_G |x − median_G|

the modified z-score of Iglewicz & Hoaglin (*How to Detect and Handle Outliers*, ASQC 1993),
which a few faulty units cannot drag the way they drag a mean and standard deviation. Noise
densities span decades and are positive, so the metrics are taken as log10:

- ``log10 mean(gyro_random_walk_{x,y,z})``, ``log10 mean(accel_random_walk_{x,y,z})``.

The turn-on gyro bias is *not* scored: it is a property of each unit, the same on all its
flights, with a wide natural spread (a consumer part's ±3 deg/s is 3σ of its datasheet), so
within a model the flights cluster by vehicle and the MAD of a few clusters makes any unit look
extreme (a 5-vehicle simulated fleet flagged every flight of one healthy vehicle at z ≈ 20).
A unit's bias is judged against its datasheet, not against the fleet.

The score is the largest |z| over the metrics (``driver`` names it); a row is an outlier when
the score exceeds :data:`OUTLIER_Z` (3.5, Iglewicz & Hoaglin's recommendation). A group needs
at least :data:`MIN_GROUP` rows with the metric, and a non-zero MAD, for a score; otherwise the
score is null and ``reason`` says why.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from uasnav.fleet.output import read_dataset, write_table

OUTLIER_Z = 3.5
MIN_GROUP = 5
SCORES_FILE = "_scores.parquet"

SCORES_SCHEMA = pa.schema(
    [
        pa.field("log_hash", pa.string()),
        pa.field("path", pa.string()),
        pa.field("vehicle", pa.string()),
        pa.field("imu", pa.string()),
        pa.field("imu_model", pa.string()),
        pa.field("z_gyro_noise", pa.float64()),
        pa.field("z_accel_noise", pa.float64()),
        pa.field("score", pa.float64()),
        pa.field("driver", pa.string()),
        pa.field("outlier", pa.bool_()),
        pa.field("reason", pa.string()),
    ]
)


def _metrics(t: pa.Table) -> dict[str, np.ndarray]:
    def col(name: str) -> np.ndarray:
        return np.array([np.nan if v is None else v for v in t.column(name).to_pylist()], dtype=float)

    def log10(x: np.ndarray) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(x > 0, np.log10(np.where(x > 0, x, 1.0)), np.nan)

    g = np.mean([col(f"gyro_random_walk_{a}") for a in "xyz"], axis=0)
    a = np.mean([col(f"accel_random_walk_{a}") for a in "xyz"], axis=0)
    return {"z_gyro_noise": log10(g), "z_accel_noise": log10(a)}


def robust_z(x: np.ndarray, groups: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Modified z-scores of ``x`` within each group (module docs); NaN where undefined.

    Returns ``(z, ok_group)``, ``ok_group`` true where the row's group had a score.
    """
    z = np.full(x.shape, np.nan)
    ok = np.zeros(x.shape, dtype=bool)
    for g in np.unique(groups):
        sel = (groups == g) & np.isfinite(x)
        if sel.sum() < MIN_GROUP:
            continue
        med = np.median(x[sel])
        mad = np.median(np.abs(x[sel] - med))
        if mad > 0:
            z[sel] = 0.6745 * (x[sel] - med) / mad
            ok[groups == g] = True
    return z, ok


def scores(health: pa.Table) -> pa.Table:
    """The anomaly scores of a health table (one row per health row, same order)."""
    n = health.num_rows
    groups = np.array(health.column("imu_model").to_pylist(), dtype=object).astype(str)
    zs = {k: robust_z(v, groups)[0] for k, v in _metrics(health).items()}
    names = list(zs)
    mat = np.column_stack([np.abs(zs[k]) for k in names]) if n else np.zeros((0, len(names)))
    rows = []
    for i in range(n):
        finite = np.isfinite(mat[i])
        if finite.any():
            j = int(np.nanargmax(np.where(finite, mat[i], -1.0)))
            score, driver, reason = float(mat[i, j]), names[j], None
        else:
            score, driver = None, None
            reason = f"fewer than {MIN_GROUP} comparable IMUs of model {groups[i]!r} (or no spread)"
        rows.append(
            {
                "log_hash": health.column("log_hash")[i].as_py(),
                "path": health.column("path")[i].as_py(),
                "vehicle": health.column("vehicle")[i].as_py() if "vehicle" in health.column_names else None,
                "imu": health.column("imu")[i].as_py(),
                "imu_model": groups[i],
                **{k: (None if not np.isfinite(zs[k][i]) else float(zs[k][i])) for k in names},
                "score": score,
                "driver": driver,
                "outlier": bool(score is not None and score > OUTLIER_Z),
                "reason": reason,
            }
        )
    return pa.Table.from_pylist(rows, schema=SCORES_SCHEMA)


def write_scores(out: str | Path, schema: pa.Schema | None = None) -> dict[str, Any]:
    """Score the health dataset ``out`` and write ``out/_scores.parquet`` (atomically);
    ``schema``: the health files' schema (for a dataset without rows)."""
    health = read_dataset(out, schema)
    table = scores(health)
    write_table(table, Path(out) / SCORES_FILE)
    outl = table.filter(pc.equal(table.column("outlier"), True)) if table.num_rows else table
    return {
        "n_imus": table.num_rows,
        "n_outliers": outl.num_rows,
        "outliers": [
            {"path": r["path"], "imu": r["imu"], "score": r["score"], "driver": r["driver"]}
            for r in outl.to_pylist()
        ],
    }


def read_scores(out: str | Path) -> pa.Table:
    """The anomaly scores written beside a health dataset."""
    return pq.read_table(Path(out) / SCORES_FILE, schema=SCORES_SCHEMA)


__all__ = ["OUTLIER_Z", "SCORES_SCHEMA", "read_scores", "robust_z", "scores", "write_scores"]
