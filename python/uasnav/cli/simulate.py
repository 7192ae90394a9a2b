"""``uasnav simulate``: write a simulated IMU log (with ground truth) from a sensor preset."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from uasnav.cli._common import LATITUDE, POSITIVE, SEED, OutputPath, Real, check_outputs, echo_json

_SENSORS = {
    "single": None,
    "tetrahedron4": ("tetrahedron", 1),
    "cube6": ("cube", 1),
    "octahedron8": ("octahedron", 1),
    "dodecahedron12": ("dodecahedron", 1),
    "icosahedron20": ("icosahedron", 1),
    "planar6": ("planar", 6),
}


def _outputs(out: Path, count: int) -> list[Path]:
    if count == 1:
        return [out]
    # zero-padded so that a shell glob (OUT_s*.csv) lists the sensors in order
    width = len(str(count - 1))
    return [out.with_name(f"{out.stem}_s{i:0{width}d}{out.suffix}") for i in range(count)]


@click.command("simulate")
@click.option(
    "--preset", default="ax1", show_default=True, help="crs05-02 | ms8010 | ax1 | lsm6dsm | path.json"
)
@click.option(
    "--profile",
    type=click.Choice(["static", "soak", "ramp", "cycles", "warmup", "flight"]),
    default="static",
    show_default=True,
    help="Temperature profile (thesis §4.2.4: soak = Fig. 29, ramp = Fig. 30; cycles = repeated ramps); "
    "flight: a simulated multirotor flight (uasnav.sim.flight) with the preset's thermal gyro bias, "
    "written as OUT (IMU, magnetometer, truth) and OUT_gnss.csv.",
)
@click.option(
    "--duration", type=POSITIVE, default=None, help="Seconds; default: the profile's natural length."
)
@click.option("--rate", type=POSITIVE, default=100.0, show_default=True, help="Output sample rate (Hz).")
@click.option(
    "--seed", type=SEED, default=0, show_default=True, help="Random seed (output is deterministic)."
)
@click.option(
    "--latitude", "latitude_deg", type=LATITUDE, default=45.0, show_default=True, help="Latitude (deg)."
)
@click.option(
    "--height", "height_m", type=Real(-1e4, 1e5), default=0.0, show_default=True, help="Height (m, WGS-84)."
)
@click.option(
    "--sensors",
    type=click.Choice(sorted(_SENSORS)),
    default="single",
    show_default=True,
    help="cube6: six sensors on the faces of a cube (likewise one per face of the other "
    "Platonic solids, in the face order of `uasnav redundancy fuse --shape`); planar6: six "
    "aligned sensors. Multi-sensor runs write one file per sensor: OUT_s0.ext, OUT_s1.ext, ….",
)
@click.option(
    "--table-rate",
    "table_rate_dps",
    type=Real(-1e4, 1e4),
    default=0.0,
    show_default=True,
    help="Slow motion: rate table turning about the vertical at this rate (deg/s).",
)
@click.option("--out", "out", type=OutputPath(), required=True, help="Output log (.csv or .npz).")
@click.option("--json", "as_json", is_flag=True, help="Print a JSON summary.")
def command(
    preset: str,
    profile: str,
    duration: float | None,
    rate: float,
    seed: int,
    latitude_deg: float,
    height_m: float,
    sensors: str,
    table_rate_dps: float,
    out: str,
    as_json: bool,
) -> None:
    """Simulate a static IMU with every error term and write it (with ground truth) to OUT.

    The log holds gyro (rad/s), accel (m/s²), the measured die temperature (°C) and truth_*
    columns (true rate, true specific force, gyro/accel bias, thermal bias, attitude, die and
    chamber temperature). Progress goes to stderr for long runs.
    """
    from uasnav.atomicfile import output_set
    from uasnav.io import WRITE_EXTENSIONS, write_log
    from uasnav.sim import load_preset, simulate, simulate_array

    out_path = Path(out)
    if out_path.suffix.lower() not in WRITE_EXTENSIONS:
        raise click.UsageError(f"--out: extension must be one of {', '.join(WRITE_EXTENSIONS)}")
    if profile == "flight":
        if sensors != "single" or table_rate_dps != 0.0:
            raise click.UsageError("--profile flight: one sensor, no --table-rate")
        _simulate_flight(preset, duration, rate, seed, latitude_deg, height_m, out_path, as_json)
        return
    # one file per sensor: the count ends each multi-sensor name (cube6 → 6)
    n_files = 1 if _SENSORS[sensors] is None else int(sensors.lstrip("abcdefghijklmnopqrstuvwxyz"))
    check_outputs([preset], {"--out": _outputs(out_path, n_files)})
    model = load_preset(preset)
    last = [-1]

    def progress(f: float) -> None:
        pct = int(f * 100)
        if pct // 10 > last[0]:
            last[0] = pct // 10
            click.echo(f"simulate: {pct:3d} %", err=True)

    n_est = (duration or 3600.0) * rate
    cb = progress if n_est >= 1e6 else None
    kwargs = dict(
        profile=profile,
        duration=duration,
        rate=rate,
        seed=seed,
        latitude_deg=latitude_deg,
        height_m=height_m,
        table_rate_dps=table_rate_dps,
    )
    arr = _SENSORS[sensors]
    if arr is None:
        logs = [simulate(model, progress=cb, **kwargs)]  # type: ignore[arg-type]
    else:
        logs = simulate_array(model, shape=arr[0], per_face=arr[1], progress=cb, **kwargs)  # type: ignore[arg-type]
    paths = _outputs(out_path, len(logs))
    with output_set():  # all sensors' files, or none
        for log, p in zip(logs, paths, strict=True):
            write_log(log, p)
    if cb is not None:
        sys.stderr.flush()
    summary = {
        "preset": model.name,
        "profile": profile,
        "rate_hz": rate,
        "seed": seed,
        "samples": logs[0].n,
        "duration_s": logs[0].duration,
        "sensors": len(logs),
        "files": [str(p) for p in paths],
        "temp_range_c": [float(logs[0].truth["temp_die"].min()), float(logs[0].truth["temp_die"].max())],
        "gyro_bias_mean_rad_s": [log.truth["gyro_bias"].mean(axis=0) for log in logs],
    }
    if as_json:
        echo_json(summary)
    else:
        click.echo(
            f"wrote {len(paths)} file(s) ({logs[0].n} samples, {logs[0].duration:.1f} s, preset "
            f"{model.name}, profile {profile}): {', '.join(str(p) for p in paths)}"
        )


def _simulate_flight(
    preset: str,
    duration: float | None,
    rate: float,
    seed: int,
    latitude_deg: float,
    height_m: float,
    out_path: Path,
    as_json: bool,
) -> None:
    """``--profile flight``: OUT holds gyro, accel, temp, mx/my/mz and truth_* (lat, lon deg;
    alt m; vel m/s NED; euler deg; gyro/accel bias); OUT_gnss.csv the GNSS fixes."""

    from uasnav.atomicfile import output_set
    from uasnav.io import write_log
    from uasnav.io.formats.gnss_csv import write_gnss_csv
    from uasnav.limits import check_memory
    from uasnav.sim import load_preset
    from uasnav.sim.flight import imu_log_with_truth, simulate_flight

    gnss_path = out_path.with_name(f"{out_path.stem}_gnss.csv")
    check_outputs([preset], {"--out": [out_path, gnss_path]})
    if duration is not None:  # 60 float64 columns per sample (IMU, truth, GNSS)
        check_memory(
            (duration * rate + 1) * 8 * 60, "simulate --profile flight", option="--duration or --rate"
        )
    model = load_preset(preset)
    if not -80.0 <= latitude_deg <= 80.0:
        raise click.BadParameter(
            f"--profile flight needs |latitude| <= 80, got {latitude_deg}", param_hint="--latitude"
        )
    f = simulate_flight(
        duration_s=duration,
        rate_hz=rate,
        seed=seed,
        latitude_deg=latitude_deg,
        height_m=height_m,
        preset=model,
    )
    log = imu_log_with_truth(f)
    with output_set():  # the IMU log and the GNSS file, or neither
        write_log(log, out_path)
        write_gnss_csv(gnss_path, f.gnss)
    summary = {
        "preset": model.name,
        "profile": "flight",
        "rate_hz": rate,
        "seed": seed,
        "samples": log.n,
        "duration_s": log.duration,
        "gnss_fixes": f.gnss.n,
        "files": [str(out_path), str(gnss_path)],
    }
    if as_json:
        echo_json(summary)
    else:
        click.echo(
            f"wrote a simulated flight ({log.n} samples, {log.duration:.1f} s): {out_path}, {gnss_path}"
        )


__all__ = ["command"]
