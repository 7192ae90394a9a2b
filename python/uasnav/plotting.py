"""Shared matplotlib helpers (Agg backend, no display): a new figure, saving a PNG atomically.

Each result type draws itself (``AllanResult.plot``, ``DriftResult.plot`` …) with these
helpers; this module imports no result type, so it stays on the ground floor."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def new_figure(width: float = 7.0, height: float = 4.5) -> tuple[Figure, Axes]:
    """A figure and axes on the non-interactive Agg canvas (safe on headless machines)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.add_subplot()


def save_png(fig: Figure, path: str) -> None:
    """Save a figure as PNG atomically."""
    import io

    from uasnav.atomicfile import atomic_write_bytes

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    atomic_write_bytes(path, buf.getvalue())


__all__ = ["new_figure", "save_png"]
