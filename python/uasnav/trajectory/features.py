"""Element features (θ, θ_w, |V_w|), the mirror folding of Figure 53 and the 4×8×4 class grid.

Conventions: the wind *velocity* V_W points where the air goes (eqs. 56–58 use the velocity
vector). Wind given meteorologically ("from DIR") is converted by :func:`wind_vector`.
θ is the signed turn angle (positive = right turn), θ_w the angle from the first segment to
V_W measured clockwise, in [0, 360).

Mirror folding (Figure 53): reflecting an element about its first segment turns a left turn
into a right turn and maps θ_w → 360° − θ_w. We fold every left turn (θ < 0) onto a right turn,
so that θ ∈ [0°, 180°]; straight elements (θ = 0) are symmetric, so θ_w is folded into
[0°, 180°] for them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from uasnav.errors import InputError

#: Class centres of eqs. (48)–(50).
THETA_CENTRES_DEG = np.array([0.0, 45.0, 90.0, 135.0])
THETA_W_CENTRES_DEG = np.arange(8) * 45.0
WIND_CENTRES_MS = np.array([2.5, 5.0, 7.5, 10.0])
#: Upper edge of the highest wind class (m/s): faster wind is outside the trained classes.
WIND_MAX_MS = 11.25
#: Number of cells of the grid (4 × 8 × 4 = 128, the thesis' S²).
N_CELLS = THETA_CENTRES_DEG.size * THETA_W_CENTRES_DEG.size * WIND_CENTRES_MS.size
#: Radius of the circle on which θ_w is embedded so that adjacent 45° sectors are one unit apart.
_R_WIND_DIR = 0.5 / np.sin(np.radians(22.5))


def wind_vector(speed_ms: float, from_deg: float) -> np.ndarray:
    """Wind velocity (north, east) m/s of a wind of ``speed_ms`` blowing *from* ``from_deg``."""
    if not (np.isfinite(speed_ms) and np.isfinite(from_deg)) or speed_ms < 0:
        raise InputError(f"wind must be a finite speed ≥ 0 and direction, got {speed_ms}@{from_deg}")
    to = np.radians(from_deg + 180.0)
    return np.array([speed_ms * np.cos(to), speed_ms * np.sin(to)])


@dataclass(frozen=True)
class Features:
    """Folded features of m elements.

    Attributes
    ----------
    theta_deg : ndarray, shape (m,)
        Turn angle after folding, [0, 180] degrees.
    theta_w_deg : ndarray, shape (m,)
        Wind direction relative to the first segment after folding, [0, 360) degrees.
    wind_ms : ndarray, shape (m,)
        Wind speed |V_w|, m/s.
    kind : ndarray of int, shape (m,)
        Element kind index into :data:`uasnav.trajectory.geometry.KINDS`.
    mirrored : ndarray of bool, shape (m,)
        The element was a left turn (or a straight with θ_w > 180°) and has been mirrored.
    """

    theta_deg: np.ndarray
    theta_w_deg: np.ndarray
    wind_ms: np.ndarray
    kind: np.ndarray
    mirrored: np.ndarray

    def matrix(self) -> np.ndarray:
        """The network inputs, shape (m, 5), each scaled so one class step ≈ one unit.

        Columns: θ/45°, θ_w on a circle (cos, sin) of radius 1/(2 sin 22.5°) so that adjacent
        45° sectors are one unit apart and 315° neighbours 0°, |V_w|/2.5 m/s, and the element
        kind (0 corner / straight, 4 start, 8 end: far from each other so kinds never share a
        prototype).
        """
        tw = np.radians(self.theta_w_deg)
        kind_col = np.select([self.kind == 2, self.kind == 3], [4.0, 8.0], 0.0)
        return np.column_stack(
            [
                self.theta_deg / 45.0,
                _R_WIND_DIR * np.cos(tw),
                _R_WIND_DIR * np.sin(tw),
                self.wind_ms / 2.5,
                kind_col,
            ]
        )


def fold(turn_deg: np.ndarray, theta_w_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Apply the Figure 53 symmetry: returns (θ ∈ [0,180], θ_w ∈ [0,360), mirrored)."""
    th = np.asarray(turn_deg, dtype=float)
    tw = np.mod(np.asarray(theta_w_deg, dtype=float), 360.0)
    left = th < 0
    straight = th == 0
    mirrored = left | (straight & (tw > 180.0))
    tw = np.where(mirrored, np.mod(360.0 - tw, 360.0), tw)
    return np.abs(th), tw, mirrored


def features(
    heading1_deg: np.ndarray,
    turn_deg: np.ndarray,
    kind: np.ndarray,
    wind_ne: np.ndarray,
) -> Features:
    """Features of elements from their first-segment course, turn angle and the wind.

    Parameters
    ----------
    heading1_deg, turn_deg : ndarray, shape (m,)
        Course of the first segment and signed turn (positive right), degrees.
    kind : ndarray, shape (m,)
        Kind names (see ``KINDS``) or indices.
    wind_ne : ndarray, shape (2,) or (m, 2)
        Wind velocity (north, east), m/s.
    """
    from uasnav.trajectory.geometry import KINDS

    h = np.asarray(heading1_deg, dtype=float)
    w = np.broadcast_to(np.asarray(wind_ne, dtype=float), (h.size, 2))
    if not np.isfinite(w).all():
        raise InputError("wind velocity contains NaN/inf")
    speed = np.hypot(w[:, 0], w[:, 1])
    # θ_w (eq. 56) measured clockwise from the first segment; calm air has no direction: 0.
    tw = np.where(speed > 0, np.mod(np.degrees(np.arctan2(w[:, 1], w[:, 0])) - h, 360.0), 0.0)
    th, tw, mir = fold(turn_deg, tw)
    k = np.asarray(kind)
    if k.dtype.kind in "US":
        lookup = {name: i for i, name in enumerate(KINDS)}
        try:
            k = np.array([lookup[str(x)] for x in k], dtype=int)
        except KeyError as exc:
            raise InputError(f"unknown element kind {exc.args[0]!r}; expected one of {KINDS}") from None
    return Features(theta_deg=th, theta_w_deg=tw, wind_ms=speed, kind=k.astype(int), mirrored=mir)


def cell_index(f: Features) -> np.ndarray:
    """Class cell of each element in the 4×8×4 grid of eqs. (48)–(50), plus 128 × kind.

    Cell = iθ·32 + iθw·4 + iV with the nearest class centre on each axis (θ ≥ 112.5° → 135°,
    |V_w| ≥ 8.75 → 10 m/s). Straight elements share the corner grid (θ = 0 class); start/end
    elements get their own 128-cell blocks, so the result is in [0, 512).
    """
    i_th = np.clip(np.rint(f.theta_deg / 45.0), 0, 3).astype(int)
    i_tw = np.mod(np.rint(f.theta_w_deg / 45.0), 8).astype(int)
    i_v = np.clip(np.rint(f.wind_ms / 2.5) - 1, 0, 3).astype(int)
    block = np.where(f.kind >= 2, f.kind - 1, 0)
    return block * N_CELLS + i_th * 32 + i_tw * 4 + i_v


def cell_centre(cell: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Inverse of :func:`cell_index`: (θ, θ_w, |V_w|, block) class centres of each cell."""
    c = np.asarray(cell, dtype=int)
    block, r = np.divmod(c, N_CELLS)
    i_th, r = np.divmod(r, 32)
    i_tw, i_v = np.divmod(r, 4)
    return THETA_CENTRES_DEG[i_th], THETA_W_CENTRES_DEG[i_tw], WIND_CENTRES_MS[i_v], block


__all__ = [
    "N_CELLS",
    "THETA_CENTRES_DEG",
    "THETA_W_CENTRES_DEG",
    "WIND_CENTRES_MS",
    "WIND_MAX_MS",
    "Features",
    "cell_centre",
    "cell_index",
    "features",
    "fold",
    "wind_vector",
]
