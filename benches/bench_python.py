"""Python-level benchmarks with side-by-side ratios against peer libraries, in one process.

Run: ``make bench-python`` (or ``.venv/bin/python benches/bench_python.py [--quick]``).
Prints one line per case: median wall time of uasnav, of the peer, and the ratio. The machine is
shared and noisy: we report medians of several repeats and compare within the same process.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import numpy as np


def median_time(fn: Callable[[], object], repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def bench_allan(n: int, repeat: int) -> None:
    import allantools

    from uasnav.allan import oadev

    rng = np.random.default_rng(0)
    y = rng.normal(0.1, 0.01, n)
    ours = oadev(y, rate=100.0, taus="octave")
    _, ref, _, _ = allantools.oadev(y, rate=100.0, data_type="freq", taus="octave")
    worst = float(np.max(np.abs(ours.adev - ref) / ref))
    t_ours = median_time(lambda: oadev(y, rate=100.0, taus="octave"), repeat)
    t_ref = median_time(lambda: allantools.oadev(y, rate=100.0, data_type="freq", taus="octave"), repeat)
    print(
        f"allan oadev octave n={n:.0e}: uasnav {t_ours * 1e3:8.1f} ms | allantools {t_ref * 1e3:8.1f} ms"
        f" | speed-up {t_ref / t_ours:5.1f}x | max rel diff {worst:.1e}"
    )


def bench_redundancy(m: int, repeat: int) -> None:
    """Fuse six triaxial sensors on a cube (m samples): uasnav WLS and WLS+FDI vs numpy's
    pseudo-inverse (the same WLS estimate, vectorised, without screening or FDI)."""
    from uasnav import redundancy as R

    cfg = R.configuration("cube", 1, triaxial=True)
    rng = np.random.default_rng(0)
    w = rng.standard_normal((m, 3))
    z = np.ascontiguousarray(w @ cfg.axes.T + 1e-3 * rng.standard_normal((m, cfg.n_axes)))
    sigma = np.full(cfg.n_axes, 1e-3)
    h_pinv = np.linalg.pinv(cfg.axes)
    t_np = median_time(lambda: z @ h_pinv.T, repeat)
    t_wls = median_time(lambda: R.fuse_axes(cfg, z, sigma=sigma, fdi=False), repeat)
    t_fdi = median_time(lambda: R.fuse_axes(cfg, z, sigma=sigma, fdi=True), repeat)
    diff = np.abs(R.fuse_axes(cfg, z, sigma=sigma, fdi=False).value - z @ h_pinv.T).max()
    print(
        f"redundancy m={m}: numpy pinv {t_np * 1e3:.2f} ms, uasnav WLS {t_wls * 1e3:.2f} ms "
        f"({t_wls / m * 1e9:.0f} ns/sample), WLS+FDI {t_fdi * 1e3:.2f} ms "
        f"({t_fdi / m * 1e9:.0f} ns/sample), max |diff| {diff:.2g}"
    )


CASES: dict[str, Callable[[bool], None]] = {
    "allan": lambda quick: bench_allan(10**6 if quick else 10**7, 3 if quick else 5),
    "redundancy": lambda quick: bench_redundancy(10**5 if quick else 10**6, 3 if quick else 5),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="smaller inputs, fewer repeats")
    ap.add_argument("cases", nargs="*", help=f"cases to run (default all): {', '.join(CASES)}")
    args = ap.parse_args()
    for name in args.cases or list(CASES):
        CASES[name](args.quick)


if __name__ == "__main__":
    main()
