"""``uasnav redundancy``: k_r of polyhedral configurations and fusion of redundant IMU logs."""

from __future__ import annotations

import click
import numpy as np

from uasnav.cli._common import echo_json

_SHAPES = ["tetrahedron", "cube", "octahedron", "dodecahedron", "icosahedron"]


@click.group("redundancy")
def command() -> None:
    """Redundant IMUs on regular polyhedra (thesis §4.3): k_r, fusion, FDI."""


@command.command("kr")
@click.option("--shape", type=click.Choice(_SHAPES), default="cube", show_default=True)
@click.option(
    "--per-face",
    type=float,
    default=1.0,
    show_default=True,
    help="Sensors per face, a multiple of 0.5 (Table 14's 'gyros per face').",
)
@click.option(
    "--triaxial",
    is_flag=True,
    help="Triaxial sensors per face instead of single-axis gyros along the normals.",
)
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
def kr_command(shape: str, per_face: float, triaxial: bool, as_json: bool) -> None:
    """Improvement factor k_r per IMU axis (eq. 40) and the LS covariance (HᵀH)⁻¹.

    k_r is the fraction of a single sensor's bias (or noise) σ left on each IMU axis after
    averaging all sensor axes. `--shape cube --per-face 1` is Table 14's row 2 (six gyros,
    k_r = 0.71); `--triaxial` with one per face is the thesis' six-SensorTile cube (0.41).
    """
    from uasnav.redundancy import configuration

    c = configuration(shape, per_face, triaxial=triaxial)
    k = c.k_r()
    cov = c.ls_covariance(1.0)
    if as_json:
        echo_json(
            {
                "shape": shape,
                "per_face": per_face,
                "triaxial": triaxial,
                "n_sensors": c.n_sensors,
                "n_axes": c.n_axes,
                "k_r": k,
                "ls_covariance_unit_sigma": cov,
            }
        )
        return
    kind = "triaxial sensors" if triaxial else "single-axis gyros"
    click.echo(f"{shape}, {per_face:g} {kind} per face: {c.n_sensors} sensors, {c.n_axes} axes")
    click.echo("k_r (x, y, z): " + ", ".join(f"{v:.4f}" for v in k))
    click.echo("LS k_r = √diag((HᵀH)⁻¹): " + ", ".join(f"{v:.4f}" for v in np.sqrt(np.diag(cov))))


@command.command("fuse")
@click.argument("logs", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option(
    "--shape",
    type=click.Choice([*_SHAPES, "aligned", "meta"]),
    default="cube",
    show_default=True,
    help="Polyhedron whose faces carry the triaxial sensors (LOGS in face order), 'aligned' "
    "(all sensors share the IMU frame, e.g. an autopilot's IMUs) or 'meta' (each log's "
    "'# mounting:' comment).",
)
@click.option("--fdi", is_flag=True, help="Parity-space fault detection, isolation and re-fusion.")
@click.option(
    "--p-fa", type=float, default=1e-6, show_default=True, help="False-alarm probability per sample."
)
@click.option(
    "--learn-bias",
    type=float,
    default=10.0,
    show_default=True,
    help="Seconds at the start used to learn the parity-space biases (with --fdi).",
)
@click.option(
    "--stuck",
    type=int,
    default=20,
    show_default=True,
    help="Repeated samples flagging a stuck output (0 = off).",
)
@click.option(
    "--out", "out_path", required=True, type=click.Path(dir_okay=False), help="Fused CSV (log format v1)."
)
@click.option("--json", "as_json", is_flag=True, help="Print a JSON summary.")
def fuse_command(
    logs: tuple[str, ...],
    shape: str,
    fdi: bool,
    p_fa: float,
    learn_bias: float,
    stuck: int,
    out_path: str,
    as_json: bool,
) -> None:
    """Fuse the triaxial sensor LOGS (same sample times) into one IMU written to --out.

    The output is log format v1 (t, gx gy gz, ax ay az in the IMU frame) with extra columns
    `chi2_gyro`, `chi2_accel` and `health_<i>` (per sensor bit flags: 1 non-finite,
    2 saturated, 4 stuck, 8 isolated by the parity test). Samples where no valid fusion is
    possible are left out and counted.
    """
    import json

    from uasnav.atomicfile import atomic_open
    from uasnav.errors import InputError
    from uasnav.io import read_log
    from uasnav.redundancy import FACES, configuration, from_mountings, fuse

    data = [read_log(p) for p in logs]
    n = len(data)
    if shape == "aligned":
        cfg = from_mountings(np.repeat(np.eye(3)[None], n, axis=0))
    elif shape == "meta":
        mounts = []
        for p, lg in zip(logs, data, strict=True):
            if "mounting" not in lg.meta:
                raise InputError(f"{p}: no '# mounting:' comment (needed by --shape meta)")
            m = lg.meta["mounting"]
            mounts.append(json.loads(m) if isinstance(m, str) else m)
        cfg = from_mountings(np.asarray(mounts, dtype=float))
    else:
        per_face = n / FACES[shape]
        if abs(per_face * 2 - round(per_face * 2)) > 1e-9:
            raise InputError(
                f"logs: {n} triaxial sensors do not fill the {FACES[shape]} faces of a {shape} "
                "in whole or half multiples"
            )
        cfg = configuration(shape, per_face, triaxial=True)
    res = fuse(
        data,
        cfg,
        fdi=fdi,
        p_fa=p_fa,
        stuck_samples=stuck if fdi else 0,
        parity_bias_s=learn_bias if fdi else 0.0,
        time_tol_s=1e-6,
    )
    v = res.valid
    health = res.gyro.health | res.accel.health
    cols = ["t", "gx", "gy", "gz", "ax", "ay", "az", "chi2_gyro", "chi2_accel"]
    cols += [f"health_{i}" for i in range(cfg.n_sensors)]
    block = np.column_stack(
        [res.t, res.gyro.value, res.accel.value, res.gyro.chi2, res.accel.chi2, health.astype(float)]
    )[v]
    with atomic_open(out_path, "w") as fh:
        fh.write("# uasnav log format v1 (SI units: s, rad/s, m/s^2, degC, uT)\n")
        fh.write(f"# fused_from: {' '.join(logs)}\n")
        fh.write(f"# shape: {shape}\n# fdi: {fdi}\n# dropped_samples: {int((~v).sum())}\n")
        fh.write(",".join(cols) + "\n")
        np.savetxt(fh, block, fmt="%.17g", delimiter=",")
    flagged = {i: int(np.count_nonzero(health[:, i])) for i in range(cfg.n_sensors)}
    k = cfg.k_r()
    summary = {
        "out": out_path,
        "n_samples": int(res.t.size),
        "written": int(v.sum()),
        "dropped": int((~v).sum()),
        "alarms_gyro": int(res.gyro.alarm.sum()),
        "alarms_accel": int(res.accel.alarm.sum()),
        "flagged_samples_per_sensor": flagged,
        "k_r": k,
        "gyro_sigma_rad_s": res.gyro.sigma,
        "accel_sigma_m_s2": res.accel.sigma,
    }
    if as_json:
        echo_json(summary)
        return
    click.echo(
        f"fused {n} sensors ({cfg.n_axes} axes, k_r {k[0]:.3f}): {summary['written']} of "
        f"{summary['n_samples']} samples written to {out_path}"
        + (f", {summary['dropped']} dropped" if summary["dropped"] else "")
    )
    if fdi:
        click.echo(f"parity alarms: gyro {summary['alarms_gyro']}, accel {summary['alarms_accel']}")
        for i, c in flagged.items():
            if c:
                click.echo(f"  sensor {i} ({logs[i]}): flagged on {c} samples")
