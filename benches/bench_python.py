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


def bench_thermal(n: int, repeat: int) -> None:
    """LM training of one 1-2-2-1 network (one restart) on n samples, and batch inference
    through the Rust engine vs the NumPy reference."""
    from uasnav.thermal import NeuralBiasModel, train_lm
    from uasnav.thermal.neural import forward

    rng = np.random.default_rng(0)
    t = np.linspace(-20.0, 37.0, n)
    b = 1e-3 * np.tanh((t - 10) / 8) + rng.normal(0, 5e-5, n)
    epochs = []

    def train() -> None:
        _, rec = train_lm(t, b, 2, restarts=1, seed=0)
        epochs.append(rec.epochs)

    t_train = median_time(train, repeat)
    m = NeuralBiasModel(2, restarts=1).fit(t[::10], np.stack([b[::10]] * 3, 1))
    x = np.linspace(-20.0, 37.0, 10**6)
    m.predict(x)
    t_rust = median_time(lambda: m.predict(x), repeat)
    t_np = median_time(lambda: [forward(net, x) for net in m.networks_], repeat)
    print(
        f"thermal LM 1-2-2-1 n={n:.0e}: {t_train:6.2f} s per restart ({statistics.median(epochs):.0f} epochs,"
        f" {t_train / statistics.median(epochs) * 1e3:.1f} ms/epoch)"
    )
    print(
        f"thermal predict 3 axes n=1e6: rust {t_rust * 1e3:7.1f} ms | numpy {t_np * 1e3:7.1f} ms"
        f" | speed-up {t_np / t_rust:4.1f}x ({t_rust / 3e6 * 1e9:.1f} ns per evaluation incl. derivative)"
    )


CASES: dict[str, Callable[[bool], None]] = {
    "allan": lambda quick: bench_allan(10**6 if quick else 10**7, 3 if quick else 5),
    "thermal": lambda quick: bench_thermal(10**4 if quick else 10**5, 1 if quick else 3),
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
