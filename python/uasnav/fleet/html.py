"""The ``--report FLEET.html`` page of ``uasnav fleet imu-health``: fleet distributions and outliers.

One self-contained HTML file (figures embedded as PNG), written atomically: per IMU model the
distribution of the white noise (gyro and accelerometer) and of the turn-on gyro bias with the
outliers marked, the table of outliers (anomaly score above :data:`~uasnav.fleet.anomaly.OUTLIER_Z`)
and the errors table.
"""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

import numpy as np
import pyarrow as pa

from uasnav.atomicfile import atomic_write_text

_METRICS = (
    ("gyro_random_walk", "gyro white noise (rad/√s)"),
    ("accel_random_walk", "accel white noise (m/s/√s)"),
    ("gyro_bias", "turn-on gyro bias |b| (rad/s)"),
)


def _values(t: pa.Table, stem: str) -> np.ndarray:
    cols = [
        np.array([np.nan if v is None else v for v in t.column(f"{stem}_{a}").to_pylist()]) for a in "xyz"
    ]
    if stem == "gyro_bias":
        return np.sqrt(sum(c**2 for c in cols))
    return np.mean(cols, axis=0)


def _figure_png(health: pa.Table, scores: pa.Table) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    models = sorted(set(health.column("imu_model").to_pylist()))
    outlier = np.array(scores.column("outlier").to_pylist(), dtype=bool)
    fig, axes = plt.subplots(len(models), len(_METRICS), figsize=(11, 2.6 * len(models) + 0.5), squeeze=False)
    model_col = np.array(health.column("imu_model").to_pylist(), dtype=object)
    for i, m in enumerate(models):
        sel = model_col == m
        for j, (stem, label) in enumerate(_METRICS):
            ax = axes[i][j]
            v = _values(health, stem)
            ok = sel & np.isfinite(v) & (v > 0)
            if ok.any():
                bins = np.logspace(np.log10(v[ok].min()) - 0.05, np.log10(v[ok].max()) + 0.05, 20)
                ax.hist(v[ok & ~outlier], bins=bins, color="tab:blue", label="normal")
                ax.hist(v[ok & outlier], bins=bins, color="tab:red", label="outlier")
                ax.set_xscale("log")
                ax.xaxis.set_minor_formatter(NullFormatter())  # no overlapping 2×10⁻³ … labels
            ax.set_title(f"{m}: {label}", fontsize=9)
            if i == 0 and j == 0:
                ax.legend(fontsize=8)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _table(headers: list[str], rows: list[list[object]]) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in headers)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape('' if c is None else str(c))}</td>" for c in r) + "</tr>"
        for r in rows
    )
    return f"<table><tr>{head}</tr>{body}</table>"


def render_health_report(out: str | Path) -> str:
    """The HTML page of the health dataset ``out`` (module docs)."""
    from uasnav.fleet.anomaly import OUTLIER_Z, read_scores
    from uasnav.fleet.imu_health import IMU_HEALTH
    from uasnav.fleet.output import read_dataset, read_errors

    health = read_dataset(out, IMU_HEALTH.full_schema)
    scores = read_scores(out)
    errors = read_errors(out)
    png = _figure_png(health, scores) if health.num_rows else ""
    outl = [r for r in scores.to_pylist() if r["outlier"]]
    outl.sort(key=lambda r: -(r["score"] or 0.0))
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'><title>uasnav fleet IMU health</title>",
        "<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}"
        "td,th{border:1px solid #ccc;padding:2px 6px;font-size:90%}</style></head><body>",
        "<h1>Fleet IMU health</h1>",
        f"<p>{health.num_rows} IMU(s) in {len(set(health.column('log_hash').to_pylist()))} log(s); "
        f"{len(outl)} outlier(s) (robust z-score within the IMU model above {OUTLIER_Z}); "
        f"{errors.num_rows} unreadable log(s).</p>",
    ]
    if png:
        parts.append(f"<img alt='fleet distributions' src='data:image/png;base64,{png}'>")
    parts.append("<h2>Outliers</h2>")
    parts.append(
        _table(
            ["path", "vehicle", "imu", "model", "score", "driver"],
            [
                [r["path"], r["vehicle"], r["imu"], r["imu_model"], f"{r['score']:.1f}", r["driver"]]
                for r in outl
            ],
        )
    )
    parts.append("<h2>Errors</h2>")
    parts.append(_table(["path", "error"], [[r["path"], r["error"]] for r in errors.to_pylist()]))
    parts.append("</body></html>\n")
    return "".join(parts)


def write_health_report(out: str | Path, path: str | Path) -> None:
    """Write :func:`render_health_report` of ``out`` to ``path`` atomically."""
    atomic_write_text(path, render_health_report(out))


__all__ = ["render_health_report", "write_health_report"]
