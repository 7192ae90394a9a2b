"""``uasnav fleet imu-health``: per log and IMU instance, the numbers a fleet's IMUs are judged by.

Every number comes from the one implementation uasnav has of it: static intervals from
:func:`uasnav.stationary.detect_static` (SHOE GLRT), Allan deviation from
:func:`uasnav.allan.oadev` and the IEEE 952 terms from :func:`uasnav.noise.identify`, the
temperature slope from :class:`uasnav.thermal.PolynomialBiasModel`.

Columns (SI; besides the runner's key and partition columns):

- ``imu`` (instance name), ``imu_model`` (``# imu_model:``/``preset`` of the log, else
  ``FORMAT/INSTANCE``), ``rate_hz``, ``n_samples``, ``duration_s``;
- ``static_s``: length of the longest static interval (s), where the noise is read;
  ``noise_reason``: why there are no noise terms (no static interval of at least
  :data:`MIN_STATIC_S`), else null;
- ``gyro_random_walk_{x,y,z}`` (rad/√s) and ``accel_random_walk_{x,y,z}`` (m/s/√s): the white
  noise of the static interval, per axis;
- ``{gyro,accel}_{quantization,bias_instability,rate_random_walk,rate_ramp}``: the largest
  fitted value over the axes when the term is identifiable on every axis, else null with
  ``…_reason`` saying why (a real log's static minute shows white noise only: the long-τ terms
  are then null with :func:`~uasnav.noise.identify`'s reason);
- ``gyro_bias_{x,y,z}`` (rad/s): turn-on gyro bias, the mean over the first static interval
  (it contains the Earth rate's projection, ≤ 7.3e-5 rad/s); ``accel_gravity_error_m_s2``: the
  static specific force's magnitude minus WGS-84 normal gravity at 45° (the part of the
  accelerometer bias one attitude can show);
- ``temp_min_c``, ``temp_max_c``; ``gyro_temp_slope_{x,y,z}`` (rad/s/°C): slope of the static
  gyro output against temperature when the static samples span at least
  :data:`MIN_TEMP_SPAN_C`, else null with ``temp_slope_reason``;
- ``vibration_{x,y,z}`` (m/s²): RMS of the specific force minus its 1 s moving mean (null for
  streams slower than :data:`MIN_VIBRATION_RATE_HZ`);
  ``gyro_clip_samples``/``accel_clip_samples``: samples pinned at an axis' extreme value
  (a rail reached at least :data:`CLIP_MIN_REPEATS` times: saturation).

The fleet-relative anomaly score (:mod:`uasnav.fleet.anomaly`) is computed once every log is
done, over the whole table, and written beside it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pyarrow as pa

from uasnav.fleet.logs import read_fleet_log
from uasnav.fleet.runner import Analysis, LogRows
from uasnav.imu import ImuLog

#: Shortest static interval the noise terms are read from (s).
MIN_STATIC_S = 10.0
#: Smallest temperature span over static samples for a temperature slope (°C).
MIN_TEMP_SPAN_C = 2.0
#: Slowest IMU stream whose vibration is computed (Hz): telemetry-rate streams (a .tlog's 1–4 Hz
#: RAW_IMU) cannot show airframe vibration.
MIN_VIBRATION_RATE_HZ = 20.0
#: A value at an axis' extreme at least this often is a saturated (clipped) output.
CLIP_MIN_REPEATS = 3
TERMS_LONG = ("quantization", "bias_instability", "rate_random_walk", "rate_ramp")
AXES = ("x", "y", "z")


def _schema() -> pa.Schema:
    f64, s = pa.float64(), pa.string()
    fields = [
        ("imu", s), ("imu_model", s), ("rate_hz", f64), ("n_samples", pa.int64()), ("duration_s", f64),
        ("static_s", f64), ("noise_reason", s),
    ]  # fmt: skip
    for sensor in ("gyro", "accel"):
        fields += [(f"{sensor}_random_walk_{a}", f64) for a in AXES]
        for term in TERMS_LONG:
            fields += [(f"{sensor}_{term}", f64), (f"{sensor}_{term}_reason", s)]
    fields += [(f"gyro_bias_{a}", f64) for a in AXES]
    fields += [("accel_gravity_error_m_s2", f64), ("temp_min_c", f64), ("temp_max_c", f64)]
    fields += [(f"gyro_temp_slope_{a}", f64) for a in AXES] + [("temp_slope_reason", s)]
    fields += [(f"vibration_{a}", f64) for a in AXES]
    fields += [("gyro_clip_samples", pa.int64()), ("accel_clip_samples", pa.int64())]
    return pa.schema([pa.field(n, t) for n, t in fields])


HEALTH_SCHEMA = _schema()


def _uniform(log: ImuLog) -> ImuLog:
    """The log itself if uniformly sampled (5 %), else resampled at its median rate (the Allan
    variance and the static detector need a uniform grid; real logs jitter)."""
    from uasnav.errors import InputError

    try:
        log.uniform_rate(rtol=0.05)
        return log
    except InputError:
        return log.resample(log.sample_rate)


def _clipped(x: np.ndarray) -> int:
    n = 0
    for j in range(x.shape[1]):
        col = x[:, j]
        for extreme in (col.max(), col.min()):
            k = int(np.count_nonzero(col == extreme))
            if k >= CLIP_MIN_REPEATS and extreme != 0.0:
                n += k
    return n


def _noise_columns(row: dict[str, Any], sensor: str, seg: ImuLog, rate: float) -> None:
    from uasnav.allan import oadev

    data, unit = (seg.gyro, "rad/s") if sensor == "gyro" else (seg.accel, "m/s^2")
    rep = oadev(data, rate, unit=unit).identify()
    for i, a in enumerate(AXES):
        skipped = rep.fit_skipped[i] if rep.fit_skipped else ""
        row[f"{sensor}_random_walk_{a}"] = None if skipped else float(rep.fit.random_walk[i])
    for term in TERMS_LONG:
        reasons = [rep.reason(i, term) or (rep.fit_skipped[i] if rep.fit_skipped else "") for i in range(3)]
        why = next((r for r in reasons if r), None)
        row[f"{sensor}_{term}"] = None if why else float(np.max(getattr(rep.fit, term)))
        row[f"{sensor}_{term}_reason"] = why


def imu_health_of(log: ImuLog, name: str = "imu0", model: str | None = None) -> dict[str, Any]:
    """The health row of one IMU (module table)."""
    from uasnav.earth import normal_gravity
    from uasnav.stationary import detect_static
    from uasnav.thermal import PolynomialBiasModel

    log = _uniform(log)
    rate = log.sample_rate
    row: dict[str, Any] = {f.name: None for f in HEALTH_SCHEMA}
    row.update(
        imu=name,
        imu_model=model or str(log.meta.get("imu_model") or log.meta.get("preset") or name),
        rate_hz=rate,
        n_samples=log.n,
        duration_s=log.duration,
    )
    static = detect_static(log, min_duration_s=1.0)
    spans = [(b - a, a, b) for a, b in static.intervals]
    long_enough = [(a, b) for d, a, b in spans if d >= MIN_STATIC_S]
    row["static_s"] = max((d for d, _, _ in spans), default=0.0)
    if long_enough:
        longest = max(long_enough, key=lambda ab: ab[1] - ab[0])
        seg = log.between(*longest)
        for sensor in ("gyro", "accel"):
            _noise_columns(row, sensor, seg, rate)
        first = log.between(*long_enough[0])
        bias = first.gyro.mean(axis=0)
        for i, a in enumerate(AXES):
            row[f"gyro_bias_{a}"] = float(bias[i])
        row["accel_gravity_error_m_s2"] = float(
            np.linalg.norm(first.accel.mean(axis=0)) - normal_gravity(math.radians(45.0))
        )
    else:
        row["noise_reason"] = f"no static interval of at least {MIN_STATIC_S:g} s"
        for sensor in ("gyro", "accel"):
            for term in TERMS_LONG:
                row[f"{sensor}_{term}_reason"] = row["noise_reason"]
    if log.temp is not None:
        row["temp_min_c"], row["temp_max_c"] = float(log.temp.min()), float(log.temp.max())
        temp_s, gyro_s = log.temp[static.mask], log.gyro[static.mask]
        span = float(np.ptp(temp_s)) if temp_s.size else 0.0
        if span >= MIN_TEMP_SPAN_C:
            m = PolynomialBiasModel(order=1).fit(temp_s, gyro_s)
            slope = np.asarray(m.derivative(np.array([float(np.mean(temp_s))])), dtype=float).reshape(-1)
            for i, a in enumerate(AXES):
                row[f"gyro_temp_slope_{a}"] = float(slope[i])
        else:
            row["temp_slope_reason"] = f"static samples span {span:.2f} °C < {MIN_TEMP_SPAN_C:g} °C"
    else:
        row["temp_slope_reason"] = "no temperature channel"
    from scipy.ndimage import uniform_filter1d

    if rate >= MIN_VIBRATION_RATE_HZ:
        hp = log.accel - uniform_filter1d(log.accel, size=round(rate), axis=0, mode="nearest")
        vib = np.sqrt(np.mean(hp * hp, axis=0))
        for i, a in enumerate(AXES):
            row[f"vibration_{a}"] = float(vib[i])
    row["gyro_clip_samples"] = _clipped(log.gyro)
    row["accel_clip_samples"] = _clipped(log.accel)
    return row


def imu_health_log(path: str) -> LogRows:
    """Health rows of every IMU instance of one log."""
    log = read_fleet_log(path)
    rows = []
    for name, imu in sorted(log.imus.items()):
        model = imu.meta.get("imu_model") or imu.meta.get("preset") or f"{log.format}/{name}"
        rows.append(imu_health_of(imu, name, str(model)))
    return LogRows(rows, vehicle=log.vehicle, day=log.day)


def _finish(out: Any) -> dict[str, Any]:
    from uasnav.fleet.anomaly import write_scores

    return write_scores(out, IMU_HEALTH.full_schema)


IMU_HEALTH = Analysis(
    "imu_health",
    HEALTH_SCHEMA,
    imu_health_log,
    finish=_finish,
    imports=("uasnav.io.logfile", "uasnav.allan", "uasnav.earth", "uasnav.stationary", "uasnav.thermal"),
)

__all__ = ["HEALTH_SCHEMA", "IMU_HEALTH", "MIN_STATIC_S", "imu_health_log", "imu_health_of"]
