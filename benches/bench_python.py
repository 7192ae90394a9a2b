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


def bench_trajectory(n_predict: int, n_train: int, repeat: int) -> None:
    from sklearn.neighbors import KNeighborsClassifier

    from uasnav.trajectory.features import Features, cell_index
    from uasnav.trajectory.predictor import TrajectoryPredictor
    from uasnav.trajectory.samples import ElementSamples

    rng = np.random.default_rng(0)

    def random_features(n: int) -> Features:
        return Features(
            theta_deg=rng.uniform(0, 180, n),
            theta_w_deg=rng.uniform(0, 360, n),
            wind_ms=rng.uniform(0, 11, n),
            kind=np.zeros(n, dtype=int),
            mirrored=np.zeros(n, dtype=bool),
        )

    f = random_features(n_train)
    dv = -0.5 * np.sin(np.radians(f.theta_deg) / 2) + 0.05 * f.wind_ms * np.cos(np.radians(f.theta_w_deg))
    samples = ElementSamples(
        features=f,
        length_m=np.full(n_train, 20.0),
        t_real_s=20.0 / (3.33 + dv),
        v_init_ms=np.full(n_train, 3.33),
        v_ref_ms=np.full(n_train, 3.33),
        dv_ms=dv,
        flight=np.zeros(n_train, dtype=int),
        element=np.arange(n_train),
    )
    t_fit = median_time(lambda: TrajectoryPredictor(random_state=0).fit(samples), repeat)
    model = TrajectoryPredictor(random_state=0).fit(samples)
    g = random_features(n_predict)
    length = np.full(n_predict, 20.0)
    t_pred = median_time(lambda: model.element_times(g, length, 3.33), repeat)
    acc = float(np.mean(model.lvq_.predict(g.matrix()) == cell_index(g)))
    # Peer: a 1-nearest-neighbour classifier on the same prototypes (what LVQ prediction is).
    knn = KNeighborsClassifier(n_neighbors=1).fit(model.lvq_.prototypes_, model.lvq_.prototype_labels_)
    X = g.matrix()
    t_knn = median_time(lambda: knn.predict(X), repeat)
    print(
        f"trajectory LVQ fit n={n_train:.0e} (256 prototypes, 1 epoch LVQ1): {t_fit:6.2f} s | "
        f"predict n={n_predict:.0e} elements: uasnav {t_pred * 1e3:7.1f} ms, sklearn 1-NN on the same "
        f"prototypes {t_knn * 1e3:7.1f} ms (ratio {t_knn / t_pred:4.1f}x) | cell accuracy {acc:.3f}"
    )


CASES: dict[str, Callable[[bool], None]] = {
    "trajectory": lambda quick: bench_trajectory(10**5 if quick else 10**6, 10**4 if quick else 10**5, 3),
    "allan": lambda quick: bench_allan(10**6 if quick else 10**7, 3 if quick else 5),
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
