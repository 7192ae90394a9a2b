"""Scoring of UAS/camera configurations (thesis §5.2.3.5, Figure 74, eq. 61).

Each parameter has a target and a limit. The transfer function (Figure 74) is 0 when the value
meets the target, 1 beyond the limit and linear between; the same formula serves "lower is
better" (limit > target: weight, cost, angular resolution) and "higher is better" (limit <
target: range). The total is the weighted sum (eq. 61); lower is closer to the ideal.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from uasnav.errors import InputError

#: Scored parameters, in the order of eq. 61.
PARAMETERS = ("range", "weight", "cost", "resolution")


def transfer(x, target: float, limit: float) -> np.ndarray:
    """Piecewise-linear transfer function of Figure 74.

    Parameters
    ----------
    x : array_like
        Parameter values (any shape), in the units of ``target`` and ``limit``.
    target, limit : float
        Value scoring 0 and value scoring 1; ``limit < target`` means higher is better.

    Returns
    -------
    ndarray
        ``clip((x - target) / (limit - target), 0, 1)``, same shape as ``x``.
    """
    if not (np.isfinite(target) and np.isfinite(limit)) or target == limit:
        raise InputError(
            f"transfer function needs finite target != limit, got target={target}, limit={limit}"
        )
    s = (np.asarray(x, dtype=float) - target) / (limit - target)
    # + 0.0 turns the -0.0 that clip keeps for values just inside the target into 0.0.
    return np.clip(s, 0.0, 1.0) + 0.0


@dataclass(frozen=True)
class Targets:
    """Target and limit per parameter (defaults: thesis Table 23).

    range: UAS max operating range (m), higher is better; weight: take-off mass of UAS +
    camera (g); cost: UAS + camera (USD); resolution: camera angular resolution HFOV/pixels
    (deg/px).
    """

    range_m: tuple[float, float] = (5000.0, 1500.0)
    weight_g: tuple[float, float] = (800.0, 1600.0)
    cost_usd: tuple[float, float] = (4000.0, 7000.0)
    resolution_deg: tuple[float, float] = (0.01, 0.06)


@dataclass(frozen=True)
class Weights:
    """Weights of eq. 61 (defaults: the thesis' cost-first precision-agriculture case)."""

    range: float = 1.0
    weight: float = 0.75
    cost: float = 1.25
    resolution: float = 1.0

    def __post_init__(self) -> None:
        for name in PARAMETERS:
            v = getattr(self, name)
            if not np.isfinite(v) or v < 0:
                raise InputError(f"weight {name}={v}: must be finite and >= 0")

    @classmethod
    def order_by(cls, parameter: str) -> Weights:
        """Weights with ``parameter`` the most important (1.25) as eq. 61 does for cost.

        The others keep eq. 61's values (range 1, weight 0.75, resolution 1), cost drops to 1.
        """
        if parameter not in PARAMETERS:
            raise InputError(f"--order-by {parameter!r}: expected one of {', '.join(PARAMETERS)}")
        base = {"range": 1.0, "weight": 0.75, "cost": 1.0, "resolution": 1.0}
        base[parameter] = 1.25
        return cls(**base)


@dataclass
class ScoreMatrix:
    """Scores of every UAS × camera pair; arrays of shape (n_uas, n_cam) unless noted."""

    total: np.ndarray
    range: np.ndarray  # (n_uas, 1)
    weight: np.ndarray
    cost: np.ndarray
    resolution: np.ndarray  # (1, n_cam)
    mass_g: np.ndarray
    cost_usd: np.ndarray
    weights: Weights = field(default_factory=Weights)


def score_matrix(
    uas_range_m: np.ndarray,
    uas_mass_g: np.ndarray,
    uas_cost_usd: np.ndarray,
    cam_mass_g: np.ndarray,
    cam_cost_usd: np.ndarray,
    cam_ifov_deg: np.ndarray,
    targets: Targets = Targets(),
    weights: Weights = Weights(),
    feasible: np.ndarray | None = None,
) -> ScoreMatrix:
    """Score every pair at once (eq. 61), broadcasting UAS rows against camera columns.

    Parameters
    ----------
    uas_range_m, uas_mass_g, uas_cost_usd : ndarray, shape (n_uas,)
    cam_mass_g, cam_cost_usd, cam_ifov_deg : ndarray, shape (n_cam,)
    targets, weights : Targets, Weights
    feasible : ndarray of bool, shape (n_uas, n_cam), optional
        Infeasible pairs get ``total = inf``.

    Returns
    -------
    ScoreMatrix
    """
    s_range = transfer(uas_range_m, *targets.range_m)[:, None]
    s_res = transfer(cam_ifov_deg, *targets.resolution_deg)[None, :]
    mass = uas_mass_g[:, None] + cam_mass_g[None, :]
    cost = uas_cost_usd[:, None] + cam_cost_usd[None, :]
    s_w = transfer(mass, *targets.weight_g)
    s_c = transfer(cost, *targets.cost_usd)
    total = weights.weight * s_w
    total += weights.cost * s_c
    total += weights.range * s_range
    total += weights.resolution * s_res
    if feasible is not None:
        total[~feasible] = np.inf
    return ScoreMatrix(total, s_range, s_w, s_c, s_res, mass, cost, weights)


def rank(total: np.ndarray, k: int) -> list[tuple[int, int]]:
    """The ``k`` best (lowest, finite) pairs as (uas index, camera index), best first.

    Uses a partial sort, so ranking 10⁷ pairs costs one pass plus O(k log k).
    """
    flat = total.ravel()
    n_ok = int(np.count_nonzero(np.isfinite(flat)))
    k = min(k, n_ok)
    if k <= 0:
        return []
    idx = np.argpartition(flat, k - 1)[:k] if k < flat.size else np.arange(flat.size)
    # Ties are broken by the flat index so that rankings are reproducible.
    idx = idx[np.lexsort((idx, flat[idx]))]
    return [divmod(int(i), total.shape[1]) for i in idx[:k]]


def explain(targets: Targets, weights: Weights) -> list[str]:
    """What the ranking's scores mean, one line per parameter: a value at or better than the
    target scores 0 (so configurations inside the target tie on that parameter, e.g. a $1 699
    and a $1 999 aircraft both under a $4 000 cost target), one at the limit scores 1, linear
    in between (Table 23, eq. 61); the total is the weighted sum, lower is better."""
    rows = (
        ("range", targets.range_m, "m", "longer is better", weights.range),
        ("weight", targets.weight_g, "g", "lighter is better", weights.weight),
        ("cost", targets.cost_usd, "USD", "cheaper is better", weights.cost),
        ("resolution", targets.resolution_deg, "deg/px", "finer is better", weights.resolution),
    )
    out = []
    for name, (target, limit), unit, sense, w in rows:
        out.append(
            f"{name} (weight {w:g}, {sense}): {target:g} {unit} or better scores 0 — every configuration "
            f"within the target ties on {name} —, {limit:g} {unit} scores 1, linear in between"
        )
    out.append("total = weighted sum of the four scores (eq. 61); lower is better")
    return out
