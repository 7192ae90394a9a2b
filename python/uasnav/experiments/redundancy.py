"""Redundant IMUs on regular polyhedra (thesis §4.3, Tables 14–15, Figs. 49–51), computed.

Every number comes from :mod:`uasnav.redundancy` and the project simulator
(:func:`uasnav.sim.simulate_array`, preset ``lsm6dsm``: the STMicroelectronics LSM6DSM of the
thesis' SensorTiles), static, 100 Hz, each sensor with its own random errors and the
simulator's truth to compare with. :func:`run` performs, in this order (the order of the
random seeds the report was made with):

1. :func:`geometry` — Table 14 and ``k_r`` of every Platonic solid (eq. 40);
2. :func:`cube_array` + :func:`table15` — six sensors on a cube, free-inertial attitude of one
   sensor against the fused cube (Table 15, Figs. 50–51), with a Monte Carlo over faces;
3. :func:`improvement` — measured noise, bias and time ratios against ``k_r`` theory;
4. :func:`fdi` — one sensor failing mid-run, fusion with and without parity-space FDI;
5. :func:`kalman` — Kalman fusion with per-axis bias states (partial self-calibration);
6. :func:`alignment` — relative alignment (eqs. 44–45) with known mounting errors.

>>> g = geometry()
>>> [round(r.k_r, 2) for r in g.table14]
[1.0, 0.71, 0.58, 0.5, 0.41]
>>> all(r.match for r in g.table14)
True
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uasnav import redundancy as R
from uasnav.attitude import DriftResult, crossing_table, drift
from uasnav.experiments.thesis import TABLE14, TABLE15
from uasnav.imu import ImuLog
from uasnav.sim import inject_fault, load_preset, simulate_array

FloatArray = NDArray[np.float64]

DEG = math.pi / 180
#: Simulated sensor of every experiment (the thesis' SensorTile IMU).
PRESET = "lsm6dsm"
#: Sample rate of every simulated array (Hz).
RATE_HZ = 100.0
#: Samples of the ZUPT-style initialisation (10 s at 100 Hz) that removes turn-on biases.
N_INIT = 1000

#: What each Table 14 row builds (:func:`uasnav.redundancy.configuration` of the cube).
ARRANGEMENT = {
    1: "one gyro on each of faces +x, +y, +z",
    2: "one gyro on every face (2 per axis)",
    3: "two on +x, +y, +z; one on −x, −y, −z",
    4: "two on every face (4 per axis)",
    5: "three on every face (6 per axis) ≡ six triaxial sensors",
}

Progress = Callable[[str], None]


# --- geometry -----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Table14Row:
    """One row of Table 14 (single-axis gyros along the cube's face normals).

    Attributes
    ----------
    config : int
        Row number of the thesis.
    per_face : float
        Gyros per face.
    total : int
        Total number of gyros.
    arrangement : str
        Which faces carry them (ours).
    k_r_thesis, k_r : float
        Improvement factor per IMU axis (eq. 40, dimensionless): thesis, ours.
    match : bool
        ``round(k_r, 2) == k_r_thesis``.
    """

    config: int
    per_face: float
    total: int
    arrangement: str
    k_r_thesis: float
    k_r: float
    match: bool


@dataclass(frozen=True)
class PolyhedronKr:
    """``k_r`` (x axis, dimensionless) of ``per_face`` sensors on every face of ``shape``."""

    shape: str
    per_face: int
    k_r_single_axis: float
    k_r_triaxial: float


@dataclass(frozen=True)
class GeometryResult:
    """Table 14 and every Platonic solid's ``k_r``.

    Attributes
    ----------
    table14 : tuple of Table14Row
    polyhedra : tuple of PolyhedronKr
        Every shape of :data:`uasnav.redundancy.SHAPES` × 1, 2, 3 sensors per face.
    cube_mountings : ndarray, shape (6, 3, 3)
        Mountings (IMU → sensor) of six triaxial sensors on the cube (Figure 49).
    """

    table14: tuple[Table14Row, ...]
    polyhedra: tuple[PolyhedronKr, ...]
    cube_mountings: FloatArray


def table14() -> list[tuple[int, float, int, float, float]]:
    """Rows ``(config, gyros per face, total gyros, k_r thesis, k_r ours)`` of Table 14.

    Each thesis row is rebuilt as the arrangement its gyro count implies (see
    :mod:`uasnav.redundancy`) and its ``k_r`` (eq. 40) computed from the geometry.
    """
    rows = []
    for no, per_face, total, ref in TABLE14:
        c = R.configuration("cube", per_face)
        if c.n_axes != total:  # pragma: no cover - guards the documented arrangement
            raise AssertionError(f"Table 14 row {no}: {c.n_axes} gyros, expected {total}")
        rows.append((no, per_face, total, ref, float(c.k_r()[0])))
    return rows


def geometry() -> GeometryResult:
    """Table 14 (eqs. 38–40) and ``k_r`` of every polyhedron, from the geometry alone."""
    rows = tuple(
        Table14Row(no, pf, total, ARRANGEMENT[no], ref, ours, round(ours, 2) == ref)
        for no, pf, total, ref, ours in table14()
    )
    polys = tuple(
        PolyhedronKr(shape, pf, float(R.kr(shape, pf)[0]), float(R.kr(shape, pf, triaxial=True)[0]))
        for shape in R.SHAPES
        for pf in (1, 2, 3)
    )
    return GeometryResult(rows, polys, R.configuration("cube", 1, triaxial=True).mountings())


# --- simulated arrays ---------------------------------------------------------------------------


def array_logs(
    shape: str, per_face: float, duration: float, seed: int, **kw: Any
) -> tuple[R.SensorArray, list[ImuLog]]:
    """Static logs of ``per_face`` simulated LSM6DSM per face of ``shape`` (100 Hz, ``duration``
    s), with the array whose mountings the simulator used. ``kw`` goes to ``simulate_array``."""
    cfg = R.configuration(shape, per_face, triaxial=True)
    logs = simulate_array(
        PRESET, shape=shape, per_face=per_face, duration=duration, rate=RATE_HZ, seed=seed, **kw
    )
    return cfg, logs


def cube_array(duration: float, seed: int) -> tuple[R.SensorArray, list[ImuLog]]:
    """Six simulated LSM6DSM on the cube, one per face (the thesis' prototype)."""
    return array_logs("cube", 1, duration, seed)


def imu_rate_truth(cfg: R.SensorArray, logs: list[ImuLog]) -> FloatArray:
    """True IMU-frame rate (3,) rad/s (static: the constant Earth rate) from sensor 0's truth."""
    return cfg.mountings()[0].T @ logs[0].truth["rate_true"][0]


def _skew_vector(e: FloatArray) -> FloatArray:
    """Small-angle rotation vector (rad) of a near-identity rotation matrix."""
    return 0.5 * np.array([e[2, 1] - e[1, 2], e[0, 2] - e[2, 0], e[1, 0] - e[0, 1]])


def crossing_times(cfg: R.SensorArray, logs: list[ImuLog]) -> tuple[FloatArray, FloatArray]:
    """Times (s) to reach each attitude threshold: fused array (4,) and every single sensor
    (s, 4); NaN where not reached."""
    dt = 1.0 / RATE_HZ
    nan = float("nan")
    d_f = drift(R.fuse(logs, cfg, fdi=False).gyro.value - imu_rate_truth(cfg, logs), dt)
    t_f = np.array([nan if v is None else v for v in d_f.crossing_times])
    t_s = np.array(
        [
            [nan if v is None else v for v in drift(lg.gyro - lg.truth["rate_true"], dt).crossing_times]
            for lg in logs
        ]
    )
    return t_f, t_s


# --- Table 15 -----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Table15Row:
    """One threshold of Table 15; times in s, Δt in % (eq. 46); None = not reached."""

    threshold_rad: float
    t_red_thesis: float
    t_red: float | None
    t_thesis: float
    t: float | None
    dt_percent_thesis: float
    dt_percent: float | None
    dt_percent_median: float | None


@dataclass(frozen=True)
class Table15Variant:
    """Table 15 for one preprocessing of the outputs.

    Attributes
    ----------
    name : str
        E.g. ``"raw output (no calibration)"``.
    rows : tuple of Table15Row
        Single sensor = face 1, fused = the whole cube; the median Δt% (raw variant only) is
        over all faces of all Monte Carlo cubes.
    single, fused : DriftResult
        θ(t) of face 1 and of the fused cube.
    """

    name: str
    rows: tuple[Table15Row, ...]
    single: DriftResult
    fused: DriftResult


@dataclass(frozen=True)
class Table15Result:
    """One sensor against the fused cube (Table 15, Figs. 50–51).

    Attributes
    ----------
    duration_s : float
        Length of the cube run (s).
    n_mc : int
        Simulated cubes of the Monte Carlo median.
    t : ndarray, shape (m,)
        Sample times of face 1 (s).
    face1_gyro : ndarray, shape (m, 3)
        Face 1's triaxial gyro output (rad/s), Figure 50.
    variants : tuple of Table15Variant
        Raw outputs, then after a 10 s ZUPT initialisation of each sensor's bias.
    mc_dt_percent : tuple of tuple of float
        Per threshold of Table 15 (in its order), the raw-output Δt% of every face of every
        Monte Carlo cube that reached it (%): the spread the thesis' one-face values are judged
        against (:func:`uasnav.experiments.verdicts.within_spread`).
    """

    duration_s: float
    n_mc: int
    t: FloatArray
    face1_gyro: FloatArray
    variants: tuple[Table15Variant, ...]
    mc_dt_percent: tuple[tuple[float, ...], ...] = ()


def table15(
    cube: R.SensorArray, logs: list[ImuLog], *, seed: int = 2024, quick: bool = False
) -> Table15Result:
    """Free-inertial attitude from face 1 against the fused cube (Table 15).

    Parameters
    ----------
    cube, logs
        The cube run of :func:`cube_array` (its duration sets the table's).
    seed : int
        Seeds of the Monte Carlo cubes (``seed + 1000 + s``).
    quick : bool
        8 Monte Carlo cubes instead of 30.
    """
    dt = 1.0 / RATE_HZ
    duration = float(logs[0].t.size / RATE_HZ)
    fused = R.fuse(logs, cube, fdi=False)
    w_true = imu_rate_truth(cube, logs)
    single_err = logs[0].gyro - logs[0].truth["rate_true"]
    fused_err = fused.gyro.value - w_true
    variants = {
        "raw output (no calibration)": (single_err, fused_err),
        "after a 10 s ZUPT initialisation of each sensor's bias": (
            single_err[N_INIT:] - single_err[:N_INIT].mean(axis=0),
            fused_err[N_INIT:] - fused_err[:N_INIT].mean(axis=0),
        ),
    }
    # Monte Carlo of the raw variant: every face against the fused cube, several arrays, so
    # that the comparison does not hinge on one face's random turn-on bias.
    n_mc = 8 if quick else 30
    mc: list[list[float]] = [[] for _ in TABLE15]
    for s in range(n_mc):
        c_mc, lg_mc = (cube, logs) if s == 0 else cube_array(min(duration, 10.0), seed + 1000 + s)
        d_f = drift(R.fuse(lg_mc, c_mc, fdi=False).gyro.value - imu_rate_truth(c_mc, lg_mc), dt)
        for lg in lg_mc:
            d_s = drift(lg.gyro - lg.truth["rate_true"], dt)
            for j, (_th, _a, _b, dtp) in enumerate(crossing_table(d_f, d_s)):
                if dtp is not None:
                    mc[j].append(dtp)
    out = []
    for name, (s_err, f_err) in variants.items():
        d_single = drift(s_err, dt)
        d_fused = drift(f_err, dt)
        rows = []
        for j, (th, t_red, t_one, dtp) in enumerate(crossing_table(d_fused, d_single)):
            ref = TABLE15[th]
            med = float(np.median(mc[j])) if (mc[j] and name.startswith("raw")) else None
            rows.append(Table15Row(th, ref[0], t_red, ref[1], t_one, ref[2], dtp, med))
        out.append(Table15Variant(name, tuple(rows), d_single, d_fused))
    return Table15Result(duration, n_mc, logs[0].t, logs[0].gyro, tuple(out), tuple(tuple(m) for m in mc))


# --- improvement against theory -----------------------------------------------------------------


@dataclass(frozen=True)
class ImprovementRow:
    """Measured fused/single ratios of one configuration (all dimensionless; Δt in %).

    ``noise_ratio``: white-noise σ (Allan deviation at τ₀); ``bias_ratio``: RMS bias;
    ``time_ratio``: median t(single sensor) / median t_red(fused) of the Table 15 thresholds,
    averaged over the thresholds. All three should equal ``k_r``, and
    Δt% = 100 (1/k_r − 1).
    """

    shape: str
    per_face: int
    n_sensors: int
    k_r: float
    noise_ratio: float
    bias_ratio: float
    time_ratio: float
    dt_percent_theory: float
    dt_percent: float


@dataclass(frozen=True)
class ImprovementResult:
    """:func:`improvement`: rows, ``seeds`` simulated arrays of ``duration_s`` s per row."""

    rows: tuple[ImprovementRow, ...]
    seeds: int
    duration_s: float


def improvement(
    *, seed: int = 2024, quick: bool = False, progress: Progress | None = None
) -> ImprovementResult:
    """Improvement against ``k_r`` theory for every polyhedron with 1–3 sensors per face.

    Quick: tetrahedron and cube with one sensor per face, 10 arrays each (else 40); every
    array is 10 s, seeded ``seed + 100·s + 1``.
    """
    say = progress or (lambda _msg: None)
    sweep_shapes = ("tetrahedron", "cube") if quick else R.SHAPES
    sweep_pf = (1,) if quick else (1, 2, 3)
    seeds = 10 if quick else 40
    sweep_s = 10.0
    pts = []
    for shape in sweep_shapes:
        for pf in sweep_pf:
            say(f"redundancy: {shape} × {pf}")
            noise_ratio, b_single, b_fused, t_red, t_one = [], [], [], [], []
            for s in range(seeds):
                cfg, lg = array_logs(shape, pf, sweep_s, seed + 100 * s + 1)
                err = R.fuse(lg, cfg, fdi=False).gyro.value - imu_rate_truth(cfg, lg)
                single_sigma = np.mean([R.white_noise_sigma(x.gyro) for x in lg])
                noise_ratio.append(float(np.mean(R.white_noise_sigma(err)) / single_sigma))
                b_single += [x.truth["gyro_bias"].mean(axis=0) for x in lg]
                b_fused.append(err.mean(axis=0))
                t_f, t_s = crossing_times(cfg, lg)
                t_red.append(t_f)
                t_one.append(t_s)
            bias_ratio = float(np.sqrt(np.mean(np.square(b_fused))) / np.sqrt(np.mean(np.square(b_single))))
            # θ grows linearly with the (turn-on dominated) bias, t = θ/|b|: the median time of
            # a single sensor over the median time of the fused arrays is k_r (per threshold).
            time_ratio = float(
                np.mean(np.nanmedian(np.vstack(t_one), axis=0) / np.nanmedian(np.array(t_red), axis=0))
            )
            k_r = float(cfg.k_r()[0])
            pts.append(
                ImprovementRow(
                    shape,
                    pf,
                    cfg.n_sensors,
                    k_r,
                    float(np.mean(noise_ratio)),
                    bias_ratio,
                    time_ratio,
                    100.0 * (1 / k_r - 1),
                    100.0 * (1 / time_ratio - 1),
                )
            )
    return ImprovementResult(tuple(pts), seeds, sweep_s)


# --- FDI ----------------------------------------------------------------------------------------

#: Faults injected on sensor 3 (index 2) half-way through (``uasnav.sim.inject_fault`` options).
FAULTS: dict[str, dict[str, Any]] = {
    "bias step 2 deg/s (y axis)": {"kind": "bias step", "axis": 1},
    "stuck output": {"kind": "stuck"},
    "noise burst 1 deg/s rms (3 s)": {"kind": "noise burst", "duration": 300},
    "saturation (x at 250 deg/s)": {"kind": "saturation"},
    "dropout (NaN)": {"kind": "dropout"},
}


@dataclass(frozen=True)
class FaultRow:
    """One injected fault: maximum deviation (deg/s) of the fused rate from the no-fault fusion
    after the fault, with and without FDI, the 5σ envelope (one sensor fewer), and the
    fraction of samples where the faulty sensor is flagged."""

    name: str
    max_dev_fdi_deg_s: float
    max_dev_plain_deg_s: float
    envelope_deg_s: float
    flagged_fraction: float


@dataclass(frozen=True)
class FdiResult:
    """:func:`fdi`.

    Attributes
    ----------
    rows : tuple of FaultRow
    theta : tuple of (str, DriftResult)
        θ(t) after the initialisation: no fault, bias step with FDI, bias step without FDI.
    fault_time_s : float
        Time of the fault on the θ(t) time axis (s).
    """

    rows: tuple[FaultRow, ...]
    theta: tuple[tuple[str, DriftResult], ...]
    fault_time_s: float


def fdi(cube: R.SensorArray, logs: list[ImuLog], *, seed: int = 2024) -> FdiResult:
    """One sensor failing half-way through a moving cube run, fused with and without FDI.

    Each sensor's turn-on bias is removed over the first 10 s (ZUPT initialisation), then a
    known IMU rate profile is added through every mounting (a stuck output is then wrong; at
    rest it would be harmless). p_fa = 1e-6 per sample, χ² scale (:func:`~uasnav.redundancy.
    robust_sigma`) and parity biases learned over the first 10 s; faults seeded ``seed``.
    """
    dt = 1.0 / RATE_HZ
    w_true = imu_rate_truth(cube, logs)
    t, z, _ = R.stack_logs(logs)
    truth = np.concatenate([lg.truth["rate_true"] for lg in logs], axis=1)
    z = z - (z[:N_INIT] - truth[:N_INIT]).mean(axis=0)  # ZUPT initialisation per sensor
    motion = np.column_stack([0.5 * np.sin(0.5 * t), 0.3 * np.cos(0.3 * t), 0.2 * np.sin(0.7 * t)])
    z = z + motion @ cube.axes.T
    w_imu = motion + w_true
    k0 = len(t) // 2
    sigma = R.robust_sigma(cube, z[:N_INIT], R.white_noise_sigma(z[:N_INIT]))
    opts: dict[str, Any] = {
        "sigma": sigma,
        "saturation": 4.3,
        "stuck_samples": 10,
        "parity_bias_samples": N_INIT,
    }
    nofault = R.fuse_axes(cube, z, fdi=True, **opts)
    rows = []
    theta: tuple[tuple[str, DriftResult], ...] = ()
    after = slice(k0 + 20, None)
    envelope = float(5 * np.sqrt(nofault.variance[after].max() * 6 / 5))
    for name, spec in FAULTS.items():
        zf = inject_fault(z, sensor=2, start=k0, seed=seed, **spec)
        with_fdi = R.fuse_axes(cube, zf, fdi=True, **opts)
        without = R.fuse_axes(cube, zf, fdi=False, **opts)
        dev_fdi = float(np.nanmax(np.abs(with_fdi.value[after] - nofault.value[after])))
        dev_plain = float(np.nanmax(np.abs(without.value[after] - nofault.value[after])))
        flagged = float(np.mean(with_fdi.health[after, 2] != 0))
        rows.append(FaultRow(name, dev_fdi / DEG, dev_plain / DEG, envelope / DEG, flagged))
        if not theta:
            theta = (
                ("no fault", drift(nofault.value[N_INIT:] - w_imu[N_INIT:], dt)),
                ("bias step, FDI", drift(with_fdi.value[N_INIT:] - w_imu[N_INIT:], dt)),
                ("bias step, no FDI", drift(without.value[N_INIT:] - w_imu[N_INIT:], dt)),
            )
    return FdiResult(tuple(rows), theta, (k0 - N_INIT) * dt)


# --- Kalman -------------------------------------------------------------------------------------


@dataclass(frozen=True)
class KalmanRow:
    """One fusion method: fused rate bias and worst axis-bias error (deg/s)."""

    method: str
    rate_bias_deg_s: float
    worst_bias_error_deg_s: float


@dataclass(frozen=True)
class KalmanComparison:
    """:func:`kalman`: rows, the run length (s), and the redundancy-only filter's worst error
    against the parity part of the biases (deg/s)."""

    rows: tuple[KalmanRow, ...]
    duration_s: float
    parity_error_deg_s: float


def kalman(cube: R.SensorArray, logs: list[ImuLog]) -> KalmanComparison:
    """Plain WLS averaging vs Kalman fusion with per-axis bias states, with and without
    zero-rate updates, on the first 30 s (at most) of the static cube run."""
    dt = 1.0 / RATE_HZ
    w_true = imu_rate_truth(cube, logs)
    _, zs, _ = R.stack_logs(logs)
    m = min(3000, zs.shape[0])
    zs = zs[:m]
    b_true = np.concatenate([lg.truth["gyro_bias"][:m] for lg in logs], axis=1).mean(axis=0)
    H = cube.axes
    parity = b_true - H @ np.linalg.lstsq(H, b_true, rcond=None)[0]
    kf = R.kalman_fuse(cube, zs, dt)
    kz = R.kalman_fuse(cube, zs, dt, zero_rate=np.ones(m, bool))
    avg = R.fuse_axes(cube, zs, fdi=False).value.mean(axis=0) - w_true
    rows = (
        KalmanRow("plain averaging (WLS)", float(np.abs(avg).max() / DEG), float(np.abs(b_true).max() / DEG)),
        KalmanRow(
            "Kalman, redundancy only",
            float(np.abs(kf.rate[-1] - w_true).max() / DEG),
            float(np.abs(kf.bias[-1] - b_true).max() / DEG),
        ),
        KalmanRow(
            "Kalman + zero-rate updates (static)",
            float(np.abs(kz.rate[-1] - w_true).max() / DEG),
            float(np.abs(kz.bias[-1] - b_true).max() / DEG),
        ),
    )
    return KalmanComparison(rows, m / RATE_HZ, float(np.abs(kf.bias[-1] - parity).max() / DEG))


# --- relative alignment -------------------------------------------------------------------------


@dataclass(frozen=True)
class AlignmentRow:
    """Misalignment of one face relative to face 1 (deg): truth and worst-axis estimation
    error with ideal sensors and with the full preset."""

    face: int
    true_deg: tuple[float, float, float]
    error_ideal_deg: float
    error_preset_deg: float


@dataclass(frozen=True)
class AlignmentExperiment:
    """:func:`alignment`: rows for faces 2–6 and the worst errors (deg)."""

    rows: tuple[AlignmentRow, ...]
    max_error_ideal_deg: float
    max_error_preset_deg: float


def alignment(cube: R.SensorArray, *, seed: int = 2024) -> AlignmentExperiment:
    """Relative alignment with every sensor mounted σ = 1° per axis off its face.

    From the accelerometers' mean specific force in four static attitudes of 5 s (seed
    ``seed + 7``, noise seed per attitude), differences between attitudes cancelling the
    turn-on biases. 'Ideal': the preset without its scale-factor, misalignment and thermal
    errors.
    """
    atts = [(0.0, 0.0, 0.0), (1.2, 0.0, 0.0), (0.0, -1.0, 0.0), (0.6, 0.5, 0.0)]
    models = {
        "ideal": load_preset(PRESET).without("scale_factor", "misalignment", "thermal"),
        "preset": load_preset(PRESET),
    }
    nom = cube.mountings()
    est: dict[str, FloatArray] = {}
    true = nom
    for key, model in models.items():
        vecs = []
        for k, e in enumerate(atts):
            lg = simulate_array(
                model,
                shape="cube",
                duration=5.0,
                rate=RATE_HZ,
                seed=seed + 7,
                euler_rad=e,
                mounting_error_rad=DEG,
                noise_seed=k,
            )
            vecs.append([x.accel.mean(axis=0) for x in lg])
            true = np.array([x.meta["mounting_true"] for x in lg])
        est[key] = R.relative_alignment(np.transpose(np.array(vecs), (1, 0, 2)), nominal=cube).misalignment
    rows = []
    for i in range(1, 6):
        phi = _skew_vector((true[i] @ true[0].T) @ (nom[i] @ nom[0].T).T)
        err = [float(np.abs(est[k][i] - phi).max() / DEG) for k in models]
        phi_deg = phi / DEG
        rows.append(
            AlignmentRow(i + 1, (float(phi_deg[0]), float(phi_deg[1]), float(phi_deg[2])), err[0], err[1])
        )
    return AlignmentExperiment(
        tuple(rows), max(r.error_ideal_deg for r in rows), max(r.error_preset_deg for r in rows)
    )


# --- everything ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class RedundancyResult:
    """Every redundancy experiment of the report (thesis §4.3)."""

    geometry: GeometryResult
    table15: Table15Result
    improvement: ImprovementResult
    fdi: FdiResult
    kalman: KalmanComparison
    alignment: AlignmentExperiment


def run(*, seed: int = 2024, quick: bool = False, progress: Progress | None = None) -> RedundancyResult:
    """All redundancy experiments (about 60 s; ``quick``: a 30 s cube run instead of 120 s,
    fewer Monte Carlo arrays and a reduced sweep)."""
    say = progress or (lambda _msg: None)
    geo = geometry()
    say("redundancy: six simulated LSM6DSM on a cube")
    cube, logs = cube_array(30.0 if quick else 120.0, seed)
    t15 = table15(cube, logs, seed=seed, quick=quick)
    imp = improvement(seed=seed, quick=quick, progress=progress)
    return RedundancyResult(
        geometry=geo,
        table15=t15,
        improvement=imp,
        fdi=fdi(cube, logs, seed=seed),
        kalman=kalman(cube, logs),
        alignment=alignment(cube, seed=seed),
    )


__all__ = [
    "ARRANGEMENT",
    "FAULTS",
    "N_INIT",
    "PRESET",
    "RATE_HZ",
    "AlignmentExperiment",
    "AlignmentRow",
    "FaultRow",
    "FdiResult",
    "GeometryResult",
    "ImprovementResult",
    "ImprovementRow",
    "KalmanComparison",
    "KalmanRow",
    "PolyhedronKr",
    "RedundancyResult",
    "Table14Row",
    "Table15Result",
    "Table15Row",
    "Table15Variant",
    "alignment",
    "array_logs",
    "crossing_times",
    "cube_array",
    "fdi",
    "geometry",
    "improvement",
    "imu_rate_truth",
    "kalman",
    "run",
    "table15",
]
