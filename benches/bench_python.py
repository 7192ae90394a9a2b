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


def bench_zupt(n: int, n_peer: int, repeat: int) -> None:
    """Whole-log ZUPT (100 Hz, 1 Hz updates) against a filterpy loop of the same 15-state
    model. The filterpy loop only does the Kalman algebra with a fixed dense Φ (no strapdown
    mechanisation, no re-linearisation): a lower bound on a Python implementation's cost."""
    from filterpy.kalman import KalmanFilter

    from uasnav import zupt
    from uasnav.imu import ImuLog

    dt = 0.01
    rng = np.random.default_rng(0)
    lat = np.deg2rad(45.0)
    w_ie = 7.292115e-5 * np.array([np.cos(lat), 0.0, -np.sin(lat)])
    gyro = w_ie + 1e-3 + rng.normal(0, 9.25e-4 / np.sqrt(dt), (n, 3))
    accel = np.array([0.0, 0.0, -9.8062]) + rng.normal(0, 8.3e-4 / np.sqrt(dt), (n, 3))
    log = ImuLog(t=np.arange(n) * dt, gyro=gyro, accel=accel)
    cfg = zupt.ZuptConfig(decimation=100, heading_rad=0.0)
    t_ours = median_time(lambda: zupt.run(log, "zupt", None, cfg), repeat)

    def skew(v: np.ndarray) -> np.ndarray:
        return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])

    F = np.zeros((15, 15))
    F[0:3, 3:6] = np.eye(3)
    F[3:6, 3:6] = -2 * skew(w_ie)
    F[3:6, 6:9] = -skew(np.array([0.0, 0.0, -9.8062]))
    F[3:6, 9:12] = -np.eye(3)
    F[6:9, 6:9] = -skew(w_ie)
    F[6:9, 12:15] = -np.eye(3)

    def peer() -> None:
        kf = KalmanFilter(dim_x=15, dim_z=9)
        kf.F = np.eye(15) + F * dt
        kf.Q = np.diag(np.r_[np.zeros(3), np.full(12, 1e-9)]) * dt
        kf.H = np.hstack([np.eye(9), np.zeros((9, 6))])
        kf.R = np.eye(9) * 1e-6
        kf.P = np.eye(15) * 1e-4
        z = np.zeros(9)
        for k in range(n_peer):
            kf.predict()
            if (k + 1) % 100 == 0:
                kf.update(z)

    t_peer = median_time(peer, max(1, repeat // 2))
    ours_rate, peer_rate = n / t_ours, n_peer / t_peer
    print(
        f"zupt whole log n={n:.0e}: uasnav {t_ours * 1e3:8.1f} ms ({ours_rate / 1e6:.2f} M samples/s)"
        f" | filterpy loop n={n_peer:.0e} {t_peer * 1e3:8.1f} ms ({peer_rate / 1e3:.1f} k samples/s)"
        f" | speed-up {ours_rate / peer_rate:5.1f}x"
    )


CASES: dict[str, Callable[[bool], None]] = {
    "allan": lambda quick: bench_allan(10**6 if quick else 10**7, 3 if quick else 5),
    "zupt": lambda quick: bench_zupt(
        10**5 if quick else 10**6, 10**4 if quick else 5 * 10**4, 3 if quick else 5
    ),
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
