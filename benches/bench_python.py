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
from pathlib import Path

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


def bench_noise(hours: float, repeat: int) -> None:
    """IEEE 952 identification of a 3-axis octave curve: the maximum-likelihood fit with profile
    intervals (uasnav.noise.identify, issue 14) against nav-core's weighted NNLS fit without
    intervals (the previous default), on the same curve."""
    from uasnav import _core
    from uasnav.allan import oadev
    from uasnav.noise import identify
    from uasnav.units import convert

    rate = 100.0
    n = int(hours * 3600 * rate)
    rng = np.random.default_rng(1)
    arw = float(convert(3.18, "deg/√h", "rad/√s"))
    rrw = float(convert(30.0, "deg/h/√h", "rad/s/√s"))
    walk = np.cumsum(rng.normal(0.0, rrw / np.sqrt(rate), (n, 3)), axis=0)
    y = rng.normal(0.0, arw * np.sqrt(rate), (n, 3)) + walk
    curve = oadev(y, rate=rate, taus="octave", unit="rad/s")

    def nnls() -> None:
        for j in range(3):
            _core.noise_fit_ieee952(curve.taus, np.ascontiguousarray(curve.adev[:, j] ** 2), curve.rel_error)

    t_ml = median_time(lambda: identify(curve, kind="gyro"), repeat)
    t_nnls = median_time(nnls, repeat)
    print(
        f"noise identify 3 axes, {len(curve.taus)} τ ({hours:g} h at 100 Hz): ML + 95 % intervals "
        f"{t_ml * 1e3:8.1f} ms | Rust NNLS (no intervals) {t_nnls * 1e3:8.2f} ms"
        f" | ratio {t_ml / t_nnls:6.0f}x"
    )


def bench_io(n: int, repeat: int) -> None:
    """CSV log format v1: write_log / read_log (17 significant digits, atomic, every cell
    checked with file/line/column errors) against numpy.savetxt / numpy.loadtxt of the same table."""
    import os
    import tempfile

    from uasnav import sim
    from uasnav.io import read_log, write_log

    log = sim.simulate("ax1", profile="static", duration=n / 100.0, rate=100.0, seed=1)
    with tempfile.TemporaryDirectory() as d:
        ours, peer = os.path.join(d, "log.csv"), os.path.join(d, "np.csv")
        table = np.column_stack([log.t, log.gyro, log.accel, log.temp])
        t_w = median_time(lambda: write_log(log, ours), repeat)
        t_wp = median_time(lambda: np.savetxt(peer, table, fmt="%.17g", delimiter=","), repeat)
        t_r = median_time(lambda: read_log(ours), repeat)
        t_rp = median_time(lambda: np.loadtxt(peer, delimiter=","), repeat)
    print(
        f"io csv v1 n={n:.0e} ({log.n} rows incl. truth columns): write {t_w:6.2f} s vs savetxt(8 cols) "
        f"{t_wp:6.2f} s | read {t_r:6.2f} s vs loadtxt(8 cols) {t_rp:6.2f} s"
    )


def bench_csv_pyarrow(seconds: float, repeat: int) -> None:
    """CSV log format v1 against ``pyarrow.csv.read_csv``: ``read_log`` (chunks through numpy's
    C reader, every cell checked, t strictly increasing, an ImuLog built) and
    ``load_training_data`` (calibration block means while reading) against
    ``pyarrow.csv.read_csv`` of the same file (all columns, types inferred), one process."""
    import os
    import tempfile

    import pyarrow.csv as pacsv

    from uasnav import sim
    from uasnav.io import read_log, write_log
    from uasnav.thermal import load_training_data

    log = sim.simulate("ax1", profile="soak", duration=seconds, rate=100.0, seed=1)
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "soak.csv")
        write_log(log, path)
        size = os.path.getsize(path)
        with open(path, "rb") as fh:
            head = fh.read(1 << 16).split(b"\n")
        skip = next(i for i, ln in enumerate(head) if not ln.startswith(b"#"))  # comment lines
        opts = pacsv.ReadOptions(skip_rows=skip)
        t_pa = median_time(lambda: pacsv.read_csv(path, read_options=opts), repeat)
        t_ours = median_time(lambda: read_log(path), repeat)
        t_pa2 = median_time(lambda: pacsv.read_csv(path, read_options=opts), repeat)
        t_cal = median_time(lambda: load_training_data(path, 1.0), repeat)
    t_pa = min(t_pa, t_pa2)
    print(
        f"csv v1 vs pyarrow, soak log {log.n} rows × 29 columns ({size / 1e6:.0f} MB): "
        f"read_log {t_ours:6.2f} s | calibration block means {t_cal:6.2f} s | "
        f"pyarrow.csv.read_csv {t_pa:6.2f} s | ratio {t_ours / t_pa:4.2f}x / {t_cal / t_pa:4.2f}x"
    )


def bench_sim(n: int, repeat: int) -> None:
    """Full simulator run (ax1: both triads, thermal terms, truth channels) and its flicker
    generator against allantools' Kasdin–Walter power-law noise generator (one axis)."""
    import allantools.noise

    from uasnav.sim import gauss_markov_sum, simulate

    rate = 100.0
    t_sim = median_time(lambda: simulate("ax1", duration=n / rate, rate=rate, seed=1), repeat)
    rng = np.random.default_rng(0)
    t_gm = median_time(lambda: gauss_markov_sum(rng, n, 1 / rate, 1e-5, (0.5, 2e4)), repeat)
    t_pink = median_time(lambda: allantools.noise.pink(n), repeat)
    print(
        f"simulate ax1 static n={n:.0e} (x3 axes, gyro+accel, truth): {t_sim:6.2f} s"
        f" | {n / t_sim / 1e6:5.2f} M samples/s"
    )
    print(
        f"flicker n={n:.0e}: uasnav GM sum (3 axes) {t_gm * 1e3:8.1f} ms | allantools.noise.pink (1 axis)"
        f" {t_pink * 1e3:8.1f} ms | ratio per axis {t_pink / (t_gm / 3):5.1f}x"
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


def bench_redundancy_ardupilot(repeat: int) -> None:
    """Real data: read and fuse the three IMUs of the shared ArduPilot log (the figures that
    tests/test_redundancy.py::test_ardupilot_three_imus asserts), and time it."""
    import os
    from pathlib import Path

    from uasnav.experiments.ardupilot import analyse_log

    root = Path(
        os.environ.get("UASNAV_SHARED_DATA", Path(__file__).resolve().parents[1] / ".." / "shared" / "data")
    )
    log = root.resolve() / "logs" / "ardupilot_log171.bin"
    if not log.is_file():
        print(f"redundancy_ardupilot: {log} not found (set UASNAV_SHARED_DATA)")
        return
    res = analyse_log(log)
    t = median_time(lambda: analyse_log(log), repeat)
    mdps = 180 / np.pi * 1e3
    single = ", ".join(f"IMU{i + 1} {np.mean(g) * mdps:.1f}" for i, g in enumerate(res.single_noise_gyro))
    print(
        f"redundancy ardupilot_log171 ({res.n_samples} samples, {res.rate_hz:.0f} Hz, read + fuse "
        f"{t:.2f} s): gyro white noise (mean of axes, mdeg/s) {single}, plain average "
        f"{np.mean(res.average_noise_gyro) * mdps:.1f}, fused {np.mean(res.fused_noise_gyro) * mdps:.1f} "
        f"(LS prediction {np.mean(res.predicted_noise_gyro) * mdps:.1f}); accel (mm/s²) single "
        f"{', '.join(f'{np.mean(a) * 1e3:.1f}' for a in res.single_noise_accel)}, fused "
        f"{np.mean(res.fused_noise_accel) * 1e3:.1f}; ArduPilot gates pass on "
        f"{100 * res.gyro_gate_ok_fraction:.1f} % (gyro 5 deg/s) / {100 * res.accel_gate_ok_fraction:.1f} % "
        f"(accel 0.75 m/s²) of samples, static window {res.static_gates_ok}; parity alarms "
        f"{100 * res.fdi_alarm_fraction:.0f} % (static σ) / {100 * res.robust_fdi_alarm_fraction:.0f} % "
        "(robust σ)"
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


def bench_mission(n_uas: int, n_cam: int, repeat: int) -> None:
    from uasnav.mission import Targets, Weights, rank, score_matrix

    rng = np.random.default_rng(0)
    ur, um, uc = rng.uniform(500, 8000, n_uas), rng.uniform(250, 9000, n_uas), rng.uniform(300, 20000, n_uas)
    cm, cc, ci = rng.uniform(40, 700, n_cam), rng.uniform(300, 16000, n_cam), rng.uniform(0.005, 0.08, n_cam)
    feasible = (um[:, None] * 0.3 >= cm[None, :]) & (ur[:, None] > 1500)
    t, w = Targets(), Weights()

    def ours() -> object:
        s = score_matrix(ur, um, uc, cm, cc, ci, t, w, feasible)
        return rank(s.total, 10)

    def loop(rows: int) -> None:
        # The same eq. 61 as a plain Python double loop (the thesis tool's per-pair approach).
        for i in range(rows):
            for j in range(n_cam):
                if feasible[i, j]:
                    _ = (
                        w.range * min(max((ur[i] - 5000) / -3500, 0), 1)
                        + w.weight * min(max((um[i] + cm[j] - 800) / 800, 0), 1)
                        + w.cost * min(max((uc[i] + cc[j] - 4000) / 3000, 0), 1)
                        + w.resolution * min(max((ci[j] - 0.01) / 0.05, 0), 1)
                    )

    t_ours = median_time(ours, repeat)
    rows = max(1, n_uas // 100)
    t_loop = median_time(lambda: loop(rows), 1) * n_uas / rows
    print(
        f"mission score+rank {n_uas}x{n_cam}: uasnav {t_ours * 1e3:8.1f} ms | python loop (extrapolated "
        f"from {rows} rows) {t_loop * 1e3:8.0f} ms | speed-up {t_loop / t_ours:5.0f}x"
    )


def bench_plan(repeat: int) -> None:
    """``uasnav.plan`` of the thesis field (70 m × 70 m at 0.05 m/px) and of a 400 m × 300 m
    field at 0.02 m/px: first call (imports and model load) and warm calls."""
    import time

    from uasnav.geo import frames

    def rect(w: float, h: float) -> dict:
        e = np.array([10, 10 + w, 10 + w, 10, 10])
        n = np.array([10, 10, 10 + h, 10 + h, 10])
        la, lo, _ = frames.enu_to_geodetic(e, n, 0.0, 45.0, 9.0, 0.0)
        return {
            "type": "Polygon",
            "coordinates": [[[float(x), float(y)] for x, y in zip(lo, la, strict=True)]],
        }

    t0 = time.perf_counter()
    import uasnav

    def thesis() -> object:
        return uasnav.plan(area=rect(70, 70), takeoff="45,9", resolution=0.05, start="2027-05-01T10:00Z")

    thesis()
    first = time.perf_counter() - t0
    t_thesis = median_time(thesis, repeat)
    t_large = median_time(
        lambda: uasnav.plan(
            area=rect(400, 300), takeoff="45,9", resolution=0.02, imagery="rgb", start="2027-05-01T10:00Z"
        ),
        repeat,
    )
    print(
        f"plan thesis field: first call (imports + model) {first:6.2f} s | warm {t_thesis * 1e3:7.1f} ms | "
        f"400x300 m at 0.02 m/px warm {t_large * 1e3:7.1f} ms"
    )


def bench_utm(n_intents: int, n_sub: int, repeat: int) -> None:
    """Issue 17: all conflicts among seeded synthetic intents (city 30 km, a day, 10–50 volumes
    each) from arrays in memory: the Rust space-time index (build + exact 4D tests) vs a shapely
    STRtree implementation and brute force (all pairs, Rust) on a subsample; JSON parsing and
    the delay search timed separately."""
    import json
    import os

    from uasnav.io.operational_intent import NamedIntent, parse_details
    from uasnav.utm.deconflict import earliest_delays, encounters
    from uasnav.utm.strtree import strtree_encounters
    from uasnav.utm.synthetic import subsample, synthetic_intents

    v = synthetic_intents(n_intents, seed=0)
    pairs = encounters(v)[0]
    n_conf = len(set(zip(v.intent[pairs[:, 0]].tolist(), v.intent[pairs[:, 1]].tolist(), strict=True)))
    t1 = median_time(lambda: encounters(v, threads=1), repeat)
    t2 = median_time(lambda: encounters(v, threads=2), repeat)
    print(
        f"utm {n_intents:.0e} intents, {len(v)} volumes: {pairs.shape[0]} conflicting volume pairs, "
        f"{n_conf} conflicting intent pairs | index 1 thread {t1:6.3f} s, 2 threads {t2:6.3f} s "
        f"(load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs)"
    )
    s = subsample(v, n_sub)
    t_idx = median_time(lambda: encounters(s, threads=1), repeat)
    t_tree = median_time(lambda: strtree_encounters(s), 1 if n_sub > 2000 else repeat)
    t_brute = median_time(lambda: encounters(s, brute=True), 1)
    same = np.array_equal(encounters(s)[0], strtree_encounters(s)[0]) and np.array_equal(
        encounters(s)[0], encounters(s, brute=True)[0]
    )
    print(
        f"utm subsample {n_sub} intents, {len(s)} volumes: index {t_idx * 1e3:8.1f} ms | shapely STRtree "
        f"{t_tree * 1e3:8.1f} ms ({t_tree / t_idx:5.0f}x) | brute force {t_brute * 1e3:9.1f} ms "
        f"({t_brute / t_idx:6.0f}x) | same pairs: {same}"
    )
    # delay search for the later intent of each conflicting pair (separately timed)
    later = np.unique(np.maximum(v.intent[pairs[:, 0]], v.intent[pairs[:, 1]]))[:1000]
    t_delay = median_time(lambda: earliest_delays(v, later), 1)
    print(
        f"utm delay search: {later.size} intents in {t_delay:6.2f} s "
        f"({t_delay / max(later.size, 1) * 1e3:.2f} ms each)"
    )
    # JSON parsing of F3548 intents (uas-standards types, checked), per intent
    square = [(47.0, 8.0), (47.0, 8.001), (47.001, 8.001), (47.001, 8.0)]
    base = json.dumps({
        "volumes": [{
            "volume": {
                "outline_polygon": {"vertices": [{"lat": a, "lng": b} for a, b in square]},
                "altitude_lower": {"value": 500.0, "reference": "W84", "units": "M"},
                "altitude_upper": {"value": 520.0, "reference": "W84", "units": "M"},
            },
            "time_start": {"value": "2026-11-24T12:00:00Z", "format": "RFC3339"},
            "time_end": {"value": "2026-11-24T12:01:00Z", "format": "RFC3339"},
        }] * 30,
        "priority": 0,
    })  # fmt: skip
    n_json = 200
    t_json = median_time(
        lambda: [NamedIntent(str(i), parse_details(json.loads(base))) for i in range(n_json)], 1
    )
    print(
        f"utm F3548 JSON parse + check: {t_json / n_json * 1e3:.2f} ms per 30-volume intent "
        f"(≈ {t_json / n_json * n_intents:.0f} s for {n_intents:.0e} intents)"
    )


# --- issue 19: fleet-scale processing on Dask -------------------------------------------------

_FLEET_PER_LOG = """
import json, resource, sys, time, tracemalloc, warnings
warnings.simplefilter("ignore")
from uasnav.fleet.runner import process_log
from uasnav.fleet import IMU_HEALTH, SCAN
analysis = {"scan": SCAN, "imu_health": IMU_HEALTH}[sys.argv[2]]
process_log(sys.argv[1], analysis, sys.argv[3] + "-warm")  # imports and caches: untimed
c0 = time.process_time()
r = process_log(sys.argv[1], analysis, sys.argv[3] + "-cpu")
cpu = time.process_time() - c0
tracemalloc.start()
process_log(sys.argv[1], analysis, sys.argv[3] + "-mem")
traced = tracemalloc.get_traced_memory()[1]
print(json.dumps({"status": r.status, "cpu_s": cpu, "traced_mb": traced / 2**20,
                  "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def bench_fleet(vehicles: int, flights: int, duration_s: float, repeat: int) -> None:
    """Fleet throughput (logs/s, MB/s) of ``imu-health`` and ``scan`` on LocalClusters of 1 and 2
    worker processes (cluster started and warmed up before timing), and per-log CPU-seconds and
    memory by format, in a fresh process per log after one untimed warm-up run: the task's peak
    of Python/numpy allocations (tracemalloc; the Rust core's few buffers are not counted) and
    the process' peak RSS (interpreter and libraries included)."""
    import json
    import os
    import subprocess
    import sys
    import tempfile
    from pathlib import Path

    from distributed import Client

    from uasnav import fleet

    with tempfile.TemporaryDirectory(prefix="bench-fleet-") as tmp:
        src = Path(tmp) / "fleet"
        fleet.simulate_fleet(src, vehicles, flights, seed=1, duration_s=duration_s, corrupt=False)
        mb = sum(f.stat().st_size for f in src.rglob("*.csv")) / 1e6
        n = vehicles * flights
        for analysis in (fleet.IMU_HEALTH, fleet.SCAN):
            rates = {}
            for workers in (1, 2):
                cluster = fleet.local_cluster(workers)
                client = Client(cluster)
                # warm-up (imports on every worker), not timed
                warm = [str(p) for p in sorted(src.rglob("*.csv"))[:workers]]
                fleet.run(analysis, warm, Path(tmp) / f"warm-{analysis.name}-{workers}", client=client)
                times = []
                for k in range(repeat):
                    out = Path(tmp) / f"{analysis.name}-{workers}-{k}.parquet"
                    t0 = time.perf_counter()
                    fleet.run(analysis, [src], out, client=client)
                    times.append(time.perf_counter() - t0)
                client.close()
                cluster.close()
                rates[workers] = statistics.median(times)
            print(
                f"fleet {analysis.name} {n} CSV v1 logs ({mb:.0f} MB, {duration_s:g} s at 100 Hz): "
                + " | ".join(
                    f"{w} worker(s) {n / t:5.2f} logs/s {mb / t:5.1f} MB/s" for w, t in rates.items()
                )
                + f" | speed-up 2 vs 1: {rates[1] / rates[2]:.2f}x"
            )
        shared = Path(__file__).resolve().parents[2] / "shared" / "data"
        samples = {f"csv-v1 (simulated, {duration_s:g} s 100 Hz)": str(next(src.rglob("*.csv")))}
        for label, rel in (
            ("px4-ulog (px4_sample.ulg, 69 s)", "logs/px4_sample.ulg"),
            ("ardupilot-dataflash (log171.bin, 3 IMUs)", "logs/ardupilot_log171.bin"),
            ("mavlink-tlog (phoenix mission1)", "flights/phoenix_mission1_arducopter.tlog"),
        ):
            if (shared / rel).exists():
                samples[label] = str(shared / rel)
        for label, path in samples.items():
            size = os.path.getsize(path) / 1e6
            parts = []
            for name in ("scan", "imu_health"):
                cpu, traced, rss = [], [], []
                for k in range(repeat):
                    out = Path(tmp) / f"one-{name}-{k}-{abs(hash(path))}"
                    r = subprocess.run(
                        [sys.executable, "-c", _FLEET_PER_LOG, path, name, str(out)],
                        capture_output=True, text=True, check=True,
                    )  # fmt: skip
                    d = json.loads(r.stdout.strip().splitlines()[-1])
                    cpu.append(d["cpu_s"])
                    traced.append(d["traced_mb"])
                    rss.append(d["rss_mb"])
                parts.append(
                    f"{name} {statistics.median(cpu):5.2f} CPU-s, task peak "
                    f"{statistics.median(traced):5.1f} MB (process RSS {statistics.median(rss):4.0f} MB) "
                    f"[{d['status']}]"
                )
            print(f"fleet per log {label} {size:.1f} MB: " + " | ".join(parts))


def bench_ins(n: int, n_peer: int, repeat: int) -> None:
    """Whole simulated flight through uasnav.ins.run (one FFI call, GIL released; 100 Hz IMU,
    5 Hz GNSS, 10 Hz baro) against a filterpy loop of the same 15-state error model (fixed Φ at
    100 Hz, a 6-row GNSS update every 20th step: only the Kalman algebra, no mechanisation —
    a lower bound on a Python implementation's cost). The flight is simulated once, outside
    the timing."""
    from filterpy.kalman import KalmanFilter

    from uasnav import ins
    from uasnav.sim.flight import simulate_flight

    flight = simulate_flight(duration_s=n / 100.0, seed=0)
    cfg = ins.InsConfig(decimation=100)
    t_ours = median_time(lambda: ins.run(flight, cfg), repeat)
    n_imu = flight.imu.n

    def skew(v: np.ndarray) -> np.ndarray:
        return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])

    w = 7.292115e-5 * np.array([np.cos(0.8), 0.0, -np.sin(0.8)])
    F = np.zeros((15, 15))
    F[0:3, 3:6] = np.eye(3)
    F[3:6, 3:6] = -2 * skew(w)
    F[3:6, 6:9] = -skew(np.array([0.3, -0.2, -9.8]))
    F[3:6, 9:12] = -np.eye(3)
    F[6:9, 6:9] = -skew(w)
    F[6:9, 12:15] = -np.eye(3)

    def peer() -> None:
        kf = KalmanFilter(dim_x=15, dim_z=6)
        kf.F = np.eye(15) + F * 0.01
        kf.Q = np.diag(np.r_[np.zeros(3), np.full(12, 1e-6)]) * 0.01
        kf.H = np.hstack([np.eye(6), np.zeros((6, 9))])
        kf.R = np.diag([2.25, 2.25, 6.25, 0.0225, 0.0225, 0.0225])
        kf.P = np.eye(15)
        z = np.zeros(6)
        for k in range(n_peer):
            kf.predict()
            if (k + 1) % 20 == 0:
                kf.update(z)

    t_peer = median_time(peer, max(1, repeat // 2))
    ours_rate, peer_rate = n_imu / t_ours, n_peer / t_peer
    print(
        f"ins whole flight n={n_imu:.2e}: uasnav {t_ours * 1e3:8.1f} ms ({ours_rate / 1e6:.2f} M samples/s)"
        f" | filterpy loop n={n_peer:.0e} {t_peer * 1e3:8.1f} ms ({peer_rate / 1e3:.1f} k samples/s)"
        f" | speed-up {ours_rate / peer_rate:5.1f}x"
    )


def bench_ins_log171(repeat: int) -> None:
    """Real data: read ArduPilot log171 and replay it (IMU, 5 Hz GNSS, baro, mag)."""
    from uasnav import ins
    from uasnav.io.formats.dataflash import read_dataflash_nav

    path = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "logs" / "ardupilot_log171.bin"
    t_read = median_time(lambda: read_dataflash_nav(path), repeat)
    f = read_dataflash_nav(path).between(0.0, 238.0)
    t_run = median_time(lambda: ins.run(f, ins.InsConfig.for_logged_imu()), repeat)
    print(f"ins log171: read {t_read * 1e3:8.1f} ms | replay {f.imu.n} samples {t_run * 1e3:8.1f} ms")


CASES: dict[str, Callable[[bool], None]] = {
    "trajectory": lambda quick: bench_trajectory(10**5 if quick else 10**6, 10**4 if quick else 10**5, 3),
    "allan": lambda quick: bench_allan(10**6 if quick else 10**7, 3 if quick else 5),
    "sim": lambda quick: bench_sim(10**6 if quick else 10**7, 3),
    "thermal": lambda quick: bench_thermal(10**4 if quick else 10**5, 1 if quick else 3),
    "zupt": lambda quick: bench_zupt(
        10**5 if quick else 10**6, 10**4 if quick else 5 * 10**4, 3 if quick else 5
    ),
    "redundancy": lambda quick: bench_redundancy(10**5 if quick else 10**6, 3 if quick else 5),
    "redundancy_ardupilot": lambda quick: bench_redundancy_ardupilot(1 if quick else 3),
    "noise": lambda quick: bench_noise(0.5 if quick else 2.0, 3 if quick else 5),
    "io": lambda quick: bench_io(10**4 if quick else 10**5, 1 if quick else 3),
    "csv_pyarrow": lambda quick: bench_csv_pyarrow(300.0 if quick else 3600.0, 3 if quick else 5),
    "mission": lambda quick: bench_mission(10**3 if quick else 10**4, 10**3, 3 if quick else 5),
    "plan": lambda quick: bench_plan(3 if quick else 5),
    "utm": lambda quick: bench_utm(10**4 if quick else 10**5, 500 if quick else 3000, 3),
    "fleet": lambda quick: bench_fleet(
        3 if quick else 5, 2 if quick else 8, 40.0 if quick else 120.0, 1 if quick else 3
    ),
    "ins": lambda quick: bench_ins(
        10**5 if quick else 10**6, 10**4 if quick else 5 * 10**4, 3 if quick else 5
    ),
    "ins_log171": lambda quick: bench_ins_log171(1 if quick else 3),
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
