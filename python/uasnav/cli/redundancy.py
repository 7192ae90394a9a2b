"""``uasnav redundancy``: k_r of polyhedral configurations and fusion of redundant IMU logs."""

from __future__ import annotations

import click
import numpy as np

from uasnav.cli._common import NON_NEGATIVE, PROBABILITY, OutputPath, Real, check_outputs, echo_json

_SHAPES = ["tetrahedron", "cube", "octahedron", "dodecahedron", "icosahedron"]


@click.group("redundancy")
def command() -> None:
    """Redundant IMUs on regular polyhedra (thesis §4.3): k_r, fusion, FDI."""


@command.command("kr")
@click.option("--shape", type=click.Choice(_SHAPES), default="cube", show_default=True)
@click.option(
    "--per-face",
    type=Real(0.0, 1000.0, lo_open=True),
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
    "--p-fa", type=PROBABILITY, default=1e-6, show_default=True, help="False-alarm probability per sample."
)
@click.option(
    "--learn-bias",
    type=NON_NEGATIVE,
    default=10.0,
    show_default=True,
    help="Seconds at the start used to learn the parity-space biases (with --fdi; 0 = off).",
)
@click.option(
    "--stuck",
    type=click.IntRange(0),
    default=20,
    show_default=True,
    help="Repeated samples flagging a stuck output (0 = off).",
)
@click.option("--out", "out_path", required=True, type=OutputPath(), help="Fused CSV (log format v1).")
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
    from uasnav.errors import NumericalError
    from uasnav.io.formats.csv_v1 import write_csv_v1
    from uasnav.redundancy import fuse_files

    check_outputs(logs, {"--out": out_path})
    fused = fuse_files(
        logs, shape, fdi=fdi, p_fa=p_fa, learn_bias_s=learn_bias, stuck_samples=stuck, time_tol_s=1e-6
    )
    if not fused.result.valid.any():
        # An empty fused log with exit 0 would pass for a result; nothing is written.
        raise NumericalError(
            f"no sample could be fused ({fused.result.t.size} samples, all dropped); nothing written to "
            f"{out_path}" + ("" if not fdi else " (check --p-fa and --learn-bias)")
        )
    # CSV v1 whatever the extension (as always); the fused log's metadata become the
    # `# key: value` lines, the χ² and health flags extra columns.
    write_csv_v1(fused.fused_log(), out_path, extra_columns=fused.extra_columns())
    summary = {"out": out_path, **fused.summary()}
    n = len(logs)
    cfg = fused.result.config
    k = summary["k_r"]
    flagged = summary["flagged_samples_per_sensor"]
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
