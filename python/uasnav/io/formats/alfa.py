"""The ROS-topic CSV folders of the CMU ALFA dataset (mavros topics dumped with ``rostopic echo -p``):
the ``nav`` and ``imus`` views, read whole (each topic's file opened once).

One CSV per topic, named ``…mavros-imu-data_raw.csv`` etc. (an optional common prefix is
allowed); first column ``%time`` (ns, Unix epoch), then ``field.*`` columns. Times used here are
the message header stamps (``field.header.stamp``, ns), made relative to the first IMU stamp.

Frames: ROS body axes are FLU and the world frame ENU; uasnav is FRD/NED. Body vectors
``(x, y, z)_FLU → (x, −y, −z)_FRD``; world vectors ``(e, n, u)_ENU → (n, e, −u)_NED``; an
orientation ``C_FLU→ENU`` becomes ``C_FRD→NED = T·C·D`` with ``T`` the ENU→NED and ``D`` the
FRD→FLU axis swaps.

Topics read:

============================================ ===============================================
``mavros-imu-data_raw``                      gyro (rad/s), specific force (m/s²); ~10 Hz
``mavros-imu-temperature``                   die temperature (°C)
``mavros-imu-mag``                           magnetic field (body; unit as logged), in
                                             ``meta["magnetometer"]`` only (see below)
``mavros-imu-atm_pressure``                  static pressure (Pa) → ISA pressure altitude
``mavros-global_position-raw-fix``           GNSS fix; σ from ``position_covariance`` (ENU m²)
``mavros-global_position-raw-gps_vel``       GNSS velocity (ENU, m/s); no accuracy logged:
                                             :data:`ALFA_SPEED_ACC_M_S`; its z is 0
                                             throughout, so the vertical velocity is the
                                             derivative of the fixes' altitude
``mavros-global_position-global``            the autopilot's position (reference)
``mavros-local_position-velocity``           the autopilot's velocity (ENU, reference)
``mavros-imu-data``                          the autopilot's attitude (reference)
============================================ ===============================================

Heights: both fixes and the autopilot's position are ``sensor_msgs/NavSatFix`` altitudes, which
ROS defines above the WGS-84 ellipsoid (mavros adds the EGM96 undulation to the autopilot's
AMSL); they are read as ellipsoidal and compare directly.
"""

from __future__ import annotations

import csv
import os
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import DataFormatError
from uasnav.geo.datum import HeightDatum
from uasnav.imu import ImuLog
from uasnav.io.flight import BaroData, Flight, GnssData, MagData, Trajectory
from uasnav.io.formats.base import WholeFileFormat
from uasnav.io.views import Identity

FloatArray = NDArray[np.float64]

#: The speed accuracy assumed for ``raw/gps_vel`` (m/s): the topic carries none.
ALFA_SPEED_ACC_M_S = 0.3
_MAX_BYTES = 200 * 1024 * 1024


def _topic_file(folder: Path, topic: str) -> Path | None:
    hits = sorted(folder.glob(f"*{topic}.csv"))
    exact = [h for h in hits if h.name == f"{topic}.csv" or h.name.endswith(f"-{topic}.csv")]
    return (exact or hits or [None])[0]


def _read_topic(
    folder: Path, topic: str, fields: list[str], required: bool = True
) -> dict[str, FloatArray] | None:
    path = _topic_file(folder, topic)
    if path is None:
        if required:
            raise DataFormatError(f"ALFA folder: no {topic}.csv", path=str(folder), column=topic)
        return None
    if path.stat().st_size > _MAX_BYTES:
        raise DataFormatError(f"{topic}: file larger than {_MAX_BYTES} bytes", path=str(path))
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            reader = csv.reader(fh)
            header = next(reader, None)
            if header is None:
                raise DataFormatError(f"{topic}: empty file", path=str(path))
            names = ["field.header.stamp", *fields]
            idx = []
            for n in names:
                if n not in header:
                    raise DataFormatError(f"{topic}: missing column {n!r}", path=str(path), column=n)
                idx.append(header.index(n))
            rows = []
            for line_no, row in enumerate(reader, start=2):
                try:
                    rows.append([float(row[i]) for i in idx])
                except (ValueError, IndexError):
                    raise DataFormatError(
                        f"{topic}: non-numeric or missing cell", path=str(path), line=line_no
                    ) from None
    except UnicodeDecodeError:
        raise DataFormatError(f"{topic}: not UTF-8 text", path=str(path)) from None
    a = np.asarray(rows, dtype=np.float64).reshape(-1, len(names))
    if not np.isfinite(a).all():
        bad = int(np.argwhere(~np.isfinite(a))[0, 0])
        raise DataFormatError(f"{topic}: non-finite value", path=str(path), line=bad + 2)
    out = {n: a[:, k] for k, n in enumerate(names)}
    out["t"] = out.pop("field.header.stamp") * 1e-9
    # Keep strictly increasing stamps (ROS may repeat a stamp).
    t = out["t"]
    keep = np.r_[True, np.diff(t) > 0] if t.size else np.zeros(0, bool)
    if not keep.all():
        keep = np.zeros(t.size, dtype=bool)
        last = -np.inf
        for i, x in enumerate(t):
            if x > last:
                keep[i], last = True, x
    return {k: v[keep] for k, v in out.items()}


def _xyz(d: dict[str, FloatArray], stem: str) -> FloatArray:
    return np.column_stack([d[f"{stem}.x"], d[f"{stem}.y"], d[f"{stem}.z"]])


_FLU_TO_FRD = np.diag([1.0, -1.0, -1.0])
_ENU_TO_NED = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def isa_pressure_altitude(p_pa: FloatArray) -> FloatArray:
    """ISA pressure altitude (m) of static pressure (Pa): ``44330.8·(1 − (p/101325)^0.190263)``."""
    return 44330.8 * (1.0 - np.power(np.asarray(p_pa, dtype=np.float64) / 101325.0, 0.190263))


def read_alfa_folder(path: str | os.PathLike[str]) -> Flight:
    """Read an ALFA ROS-topic CSV folder as a :class:`~uasnav.io.flight.Flight` (see the
    module docs).

    Raises
    ------
    DataFormatError
        Not a folder, a missing topic file or column (named), a non-numeric cell (file and
        line), fewer than 2 IMU samples or GNSS fixes.
    """
    folder = Path(path)
    if not folder.is_dir():
        raise DataFormatError("not an ALFA ROS-topic CSV folder", path=str(folder))
    vec = [f"field.angular_velocity.{a}" for a in "xyz"] + [f"field.linear_acceleration.{a}" for a in "xyz"]
    raw = _read_topic(folder, "mavros-imu-data_raw", vec)
    assert raw is not None
    if raw["t"].size < 2:
        raise DataFormatError("mavros-imu-data_raw: fewer than 2 samples", path=str(folder))
    t0 = float(raw["t"][0])
    gyro = _xyz(raw, "field.angular_velocity") @ _FLU_TO_FRD
    accel = _xyz(raw, "field.linear_acceleration") @ _FLU_TO_FRD
    temp_t = _read_topic(folder, "mavros-imu-temperature", ["field.temperature"], required=False)
    temp = None
    if temp_t is not None and temp_t["t"].size >= 2:
        temp = np.interp(raw["t"], temp_t["t"], temp_t["field.temperature"])
    imu = ImuLog(
        raw["t"] - t0,
        gyro,
        accel,
        temp,
        meta={"source": str(folder), "format": "alfa-ros-csv", "frame": "FRD (from ROS FLU)"},
    )
    fix = _read_topic(
        folder,
        "mavros-global_position-raw-fix",
        [
            "field.latitude",
            "field.longitude",
            "field.altitude",
            "field.position_covariance0",
            "field.position_covariance4",
            "field.position_covariance8",
        ],
    )
    vel = _read_topic(
        folder, "mavros-global_position-raw-gps_vel", [f"field.twist.linear.{a}" for a in "xyz"]
    )
    assert fix is not None and vel is not None
    if fix["t"].size < 2:
        raise DataFormatError("mavros-global_position-raw-fix: fewer than 2 fixes", path=str(folder))
    v_enu = np.column_stack([np.interp(fix["t"], vel["t"], vel[f"field.twist.linear.{a}"]) for a in "xyz"])
    vz_missing = bool(np.all(v_enu[:, 2] == 0.0))
    if vz_missing:
        # raw/gps_vel carries no vertical velocity (z is 0 throughout): derive it from the
        # fixes' altitude (central differences), so that "0 m/s" is not fused as a measurement.
        v_enu[:, 2] = np.gradient(fix["field.altitude"], fix["t"])
    h_var = np.maximum(fix["field.position_covariance0"], fix["field.position_covariance4"])
    gnss = GnssData(
        fix["t"] - t0,
        fix["field.latitude"],
        fix["field.longitude"],
        fix["field.altitude"],
        v_enu @ _ENU_TO_NED.T,
        np.sqrt(np.maximum(h_var, 1e-4)),
        np.sqrt(np.maximum(fix["field.position_covariance8"], 1e-4)),
        np.full(fix["t"].size, ALFA_SPEED_ACC_M_S),
        alt_datum=HeightDatum.ELLIPSOID,
    )
    baro = None
    pr = _read_topic(folder, "mavros-imu-atm_pressure", ["field.fluid_pressure"], required=False)
    if pr is not None and pr["t"].size >= 2:
        baro = BaroData(pr["t"] - t0, isa_pressure_altitude(pr["field.fluid_pressure"]))
    mag = None
    mg = _read_topic(folder, "mavros-imu-mag", [f"field.magnetic_field.{a}" for a in "xyz"], required=False)
    if mg is not None and mg["t"].size >= 2:
        mag = MagData(mg["t"] - t0, _xyz(mg, "field.magnetic_field") @ _FLU_TO_FRD)
    ref = None
    glob = _read_topic(
        folder,
        "mavros-global_position-global",
        ["field.latitude", "field.longitude", "field.altitude"],
        required=False,
    )
    if glob is not None and glob["t"].size >= 2:
        rv = _read_topic(
            folder,
            "mavros-local_position-velocity",
            [f"field.twist.linear.{a}" for a in "xyz"],
            required=False,
        )
        att = _read_topic(
            folder, "mavros-imu-data", [f"field.orientation.{a}" for a in "xyzw"], required=False
        )
        v_ref = None
        if rv is not None and rv["t"].size >= 2:
            v_ref = (
                np.column_stack([np.interp(glob["t"], rv["t"], rv[f"field.twist.linear.{a}"]) for a in "xyz"])
                @ _ENU_TO_NED.T
            )
        eul = None
        if att is not None and att["t"].size >= 2:
            eul = _ned_euler_deg(att, glob["t"])
        ref = Trajectory(
            glob["t"] - t0,
            glob["field.latitude"],
            glob["field.longitude"],
            glob["field.altitude"],
            v_ref,
            eul,
            name="PX4/mavros global_position + imu/data",
            alt_datum=HeightDatum.ELLIPSOID,
        )
    # The magnetometer is returned in meta only: its unit is undocumented (|B| ≈ 5e5 as logged)
    # and the site's declination (≈ −9°) is not modelled, so as a heading aid it does more harm
    # than the GNSS course of a fixed-wing aircraft, which the filter uses instead.
    return Flight(
        imu,
        gnss,
        baro,
        None,
        reference=ref,
        imus={"imu": imu},
        meta={
            "source": str(folder),
            "format": "alfa-ros-csv",
            "imu": "imu",
            "t0_unix_s": t0,
            "magnetometer": mag,
            "note": f"IMU at {imu.sample_rate:.1f} Hz: low for strapdown integration, it limits the accuracy",
        },
    )


def _ned_euler_deg(att: dict[str, FloatArray], t: FloatArray) -> FloatArray:
    from scipy.spatial.transform import Rotation

    q = np.column_stack([att[f"field.orientation.{a}"] for a in "xyzw"])
    ok = np.linalg.norm(q, axis=1) > 0.5
    r = Rotation.from_quat(q[ok])
    c = _ENU_TO_NED @ r.as_matrix() @ _FLU_TO_FRD  # C_FRD→NED
    e = Rotation.from_matrix(c).as_euler("ZYX")[:, ::-1]
    ta = att["t"][ok]
    return np.column_stack(
        [
            np.degrees(np.arctan2(np.interp(t, ta, np.sin(e[:, i])), np.interp(t, ta, np.cos(e[:, i]))))
            for i in range(3)
        ]
    )


class AlfaFormat(WholeFileFormat):
    """A CMU ALFA ROS-topic CSV folder."""

    name = "alfa-ros-csv"
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {"nav": (), "imus": (), "imu": (), "identity": ()}

    def build_nav(self) -> Flight:
        cached = self.options.get("_nav")
        if cached is None:
            cached = self.options["_nav"] = read_alfa_folder(self.path)
        return cached  # type: ignore[no-any-return]

    def build_imus(self) -> dict[str, Any]:
        return dict(self.build_nav().imus)

    def build_imu(self) -> Any:
        return self.build_nav().imu

    def build_identity(self) -> Identity:
        return Identity(autopilot="PX4", vehicle_type="fixed-wing", clock="file")


__all__ = ["ALFA_SPEED_ACC_M_S", "AlfaFormat", "isa_pressure_altitude", "read_alfa_folder"]
