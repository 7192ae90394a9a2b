"""Matplotlib figures shared by the API, the CLI and the report (Agg backend, no display)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from uasnav.allan import AllanResult
    from uasnav.attitude import DriftResult
    from uasnav.noise import NoiseReport


def new_figure(width: float = 7.0, height: float = 4.5) -> tuple[Figure, Axes]:
    """A figure and axes on the non-interactive Agg canvas (safe on headless machines)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.add_subplot()


def allan_axes(
    res: AllanResult,
    ax: Axes | None = None,
    labels: Sequence[str] | None = None,
    errorbars: bool = True,
    report: NoiseReport | None = None,
) -> Axes:
    """Log-log Allan deviation with χ² intervals, optional fitted model and slope guides."""
    if ax is None:
        _, ax = new_figure()
    adev = res.adev if res.adev.ndim == 2 else res.adev[:, None]
    lo = res.ci_low if res.ci_low.ndim == 2 else res.ci_low[:, None]
    hi = res.ci_high if res.ci_high.ndim == 2 else res.ci_high[:, None]
    names = list(labels) if labels is not None else [f"axis {j}" for j in range(adev.shape[1])]
    for j in range(adev.shape[1]):
        (line,) = ax.loglog(res.taus, adev[:, j], "o-", ms=3, label=names[j])
        if errorbars:
            ax.fill_between(res.taus, lo[:, j], hi[:, j], color=line.get_color(), alpha=0.2, lw=0)
        if report is not None:
            model = report.model_adev()[:, j]
            ax.loglog(res.taus, model, "--", color=line.get_color(), lw=1)
    if report is not None and adev.size:
        _slope_guides(ax, res, report)
    ax.set_xlabel("cluster time τ (s)")
    ax.set_ylabel(f"Allan deviation σ(τ) ({res.unit})" if res.unit else "Allan deviation σ(τ)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def _slope_guides(ax: Axes, res: AllanResult, report: NoiseReport) -> None:
    """Dotted lines of slope −½ through N at τ = 1 s and +½ through K at τ = 3 s (axis 0)."""
    t = res.taus
    n = float(report.fit.random_walk[0])
    k = float(report.fit.rate_random_walk[0])
    b = float(report.fit.bias_instability[0])
    if n > 0:
        ax.loglog(t, n / np.sqrt(t), ":", color="grey", lw=1, label="slope −½ (N)")
    if k > 0:
        ax.loglog(t, k * np.sqrt(t / 3.0), ":", color="black", lw=1, label="slope +½ (K)")
    if b > 0:
        ax.axhline(0.664 * b, ls="-.", color="grey", lw=0.8, label="0.664·B")


def drift_axes(series: Sequence[tuple[str, DriftResult]], ax: Axes | None = None) -> Axes:
    """θ(t) curves (rad) with the accuracy thresholds as horizontal lines."""
    if ax is None:
        _, ax = new_figure()
    for label, d in series:
        ax.plot(d.t, d.theta, label=label)
    if series:
        for th in series[0][1].thresholds:
            ax.axhline(th, color="grey", ls=":", lw=0.8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("rotation angle θ (rad)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def save_png(fig: Figure, path: str) -> None:
    """Save a figure as PNG atomically."""
    import io

    from uasnav.atomicfile import atomic_write_bytes

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    atomic_write_bytes(path, buf.getvalue())


__all__ = ["allan_axes", "drift_axes", "new_figure", "save_png"]
