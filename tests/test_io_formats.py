"""Readers/writers: npz and CSV round trips bit for bit, real PX4/ArduPilot/x-io/ADIS files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from uasnav.errors import DataFormatError, InputError
from uasnav.imu import ImuLog
from uasnav.io import read_dataflash, read_log, read_npz, read_tlog, read_ulog, write_log
from uasnav.sim import simulate


def _assert_same(a: ImuLog, b: ImuLog) -> None:
    for name in ("t", "gyro", "accel", "temp"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.tobytes() == y.tobytes(), name
    assert sorted(a.truth) == sorted(b.truth)
    for k in a.truth:
        assert a.truth[k].shape == b.truth[k].shape and a.truth[k].tobytes() == b.truth[k].tobytes(), k


@pytest.mark.parametrize("ext", [".npz", ".csv"])
def test_round_trip_with_truth_is_bit_for_bit(tmp_path: Path, ext: str) -> None:
    log = simulate("ax1", profile="ramp", duration=3.0, rate=100.0, seed=9)
    path = tmp_path / f"log{ext}"
    write_log(log, path)
    back = read_log(path)
    _assert_same(log, back)
    if ext == ".npz":
        assert back.meta["mounting"] == log.meta["mounting"] and back.meta["seed"] == 9


def test_npz_errors_name_the_array(tmp_path: Path) -> None:
    p = tmp_path / "bad.npz"
    np.savez(p, t=np.arange(5.0), gyro=np.zeros((5, 3)))
    with pytest.raises(DataFormatError, match="'accel'"):
        read_npz(p)
    acc = np.zeros((5, 3))
    acc[3, 1] = np.nan
    np.savez(p, t=np.arange(5.0), gyro=np.zeros((5, 3)), accel=acc)
    with pytest.raises(DataFormatError, match="non-finite value in 'accel' at row 3"):
        read_npz(p)
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(DataFormatError, match=r"junk\.npz"):
        read_npz(tmp_path / "junk.npz")
    with pytest.raises(InputError, match="cannot write"):
        write_log(simulate("ax1", duration=1.0), tmp_path / "x.ulg")
    assert not (tmp_path / "x.ulg").exists()


def test_px4_ulog_real_file(shared_data: Path) -> None:
    log = read_ulog(shared_data / "logs" / "px4_sample.ulg")
    assert log.n == 17070 and log.sample_rate == pytest.approx(250.0, rel=1e-6)
    # handheld: |specific force| averages about 1 g, gyro bias small
    assert np.median(np.linalg.norm(log.accel, axis=1)) == pytest.approx(9.81, abs=0.3)
    assert log.mag is not None and 10 < np.median(np.linalg.norm(log.mag, axis=1)) < 100  # µT
    small = read_log(shared_data / "logs" / "px4_sample_log_small.ulg")
    assert small.temp is not None and 39.5 < small.temp.mean() < 41.0


def test_ardupilot_dataflash_three_imus_with_temperature(shared_data: Path) -> None:
    logs = read_dataflash(shared_data / "logs" / "ardupilot_log171.bin")
    assert sorted(logs) == ["IMU", "IMU2", "IMU3"]
    for log in logs.values():
        assert log.n == 11916 and log.sample_rate == pytest.approx(50.0, rel=1e-3)
        assert log.temp is not None
    t3 = logs["IMU3"].temp
    assert (
        t3 is not None
        and t3.min() == pytest.approx(25.5, abs=0.1)
        and t3.max() == pytest.approx(42.0, abs=0.1)
    )
    assert read_log(shared_data / "logs" / "ardupilot_log171.bin").meta["message"] == "IMU"


def test_mavlink_tlog_split_at_reboot(shared_data: Path) -> None:
    logs = read_tlog(shared_data / "flights" / "phoenix_mission1_arducopter.tlog")
    assert "SCALED_IMU2" in logs and "SCALED_IMU2#2" in logs
    log = logs["SCALED_IMU2"]
    assert np.median(np.linalg.norm(log.accel, axis=1)) == pytest.approx(9.8, abs=0.4)


def test_xio_and_adis_real_files(shared_data: Path) -> None:
    x = read_log(shared_data / "imu" / "xio_fusion_sensor_data.csv")
    assert x.meta["format"] == "xio-csv" and x.mag is not None
    assert x.accel[0, 2] == pytest.approx(0.9970807 * 9.80665)
    assert x.gyro[0, 1] == pytest.approx(np.deg2rad(-0.1517251))
    assert np.max(np.abs(x.gyro)) == pytest.approx(np.deg2rad(365), rel=0.05)
    a = read_log(shared_data / "imu" / "adis16405_static_imu1.npz")
    assert a.n == 1_000_000 and a.sample_rate == pytest.approx(100.0)
    np.testing.assert_allclose(np.rad2deg(a.gyro.mean(axis=0)), [0.40, -0.42, -0.29], atol=0.02)


def test_xio_errors_name_line_and_column(tmp_path: Path) -> None:
    head = (
        "Time (s),Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s),"
        "Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)\n"
    )
    p = tmp_path / "x.csv"
    p.write_text(head + "0,1,2,3,0,0,1\n0.01,1,abc,3,0,0,1\n")
    with pytest.raises(DataFormatError, match=r"line 3, column 'Gyroscope Y \(deg/s\)'.*'abc'"):
        read_log(p)
    p.write_text(head + "0,1,2,3,0,0,1\n0,1,2,3,0,0,1\n")
    with pytest.raises(DataFormatError, match=r"line 3.*not increasing"):
        read_log(p)


def test_dataflash_flight_and_other_messages_in_seconds(shared_data: Path) -> None:
    from uasnav.io import read_dataflash_messages, read_flight
    from uasnav.io.flight import Flight

    path = shared_data / "logs" / "ardupilot_log171.bin"
    tables = read_dataflash_messages(path, ["BARO", "MAG", "ATT", "MSG"])
    assert sorted(tables) == ["ATT", "BARO", "MAG"]  # MSG: text only, no time in this (3.3) log
    baro = tables["BARO"]
    assert baro["t"].size == 2383 and np.all(np.diff(baro["t"]) > 0)
    assert baro["t"][0] == pytest.approx(11.477)  # TimeMS 11477 → s, like the IMU time stamps
    assert 94e3 < np.median(baro["Press"]) < 96e3  # Pa, Canberra
    assert {"Roll", "Pitch", "Yaw"} <= set(tables["ATT"])
    flight = read_flight(path)
    assert isinstance(flight, Flight) and flight.t.size > 1000 and not flight.waypoints
    with pytest.raises(AttributeError):
        flight.cruise_ms = 3.0  # type: ignore[misc]  # a read log is immutable


def test_tlog_flight_mission(shared_data: Path) -> None:
    from uasnav.io import read_flight

    log = read_flight(shared_data / "flights" / "phoenix_mission1_arducopter.tlog")
    assert sorted(log.waypoints) == [2, 3] and log.cruise_ms == pytest.approx(5.0)
    assert len(log.reached) == 16 and log.reached == sorted(log.reached)
    assert np.all(np.diff(log.t) > 0) and log.vel_ned.shape == (log.t.size, 3)


def test_binary_log_errors_name_the_file(tmp_path: Path) -> None:
    from uasnav.io import read_flight

    junk = tmp_path / "junk.bin"
    junk.write_bytes(bytes(range(64)))
    with pytest.raises(DataFormatError, match=r"junk\.bin: no IMU/IMU2/IMU3 messages"):
        read_dataflash(junk)
    with pytest.raises(DataFormatError, match=r"junk\.bin: no GPS messages"):
        read_flight(junk)
    with pytest.raises(DataFormatError, match="no such file"):
        read_dataflash(tmp_path / "missing.bin")
    with pytest.raises(InputError, match="no such telemetry file"):
        read_flight(tmp_path / "missing.tlog")


def test_flight_csv_reader(tmp_path: Path) -> None:
    from uasnav.io import read_flight

    p = tmp_path / "f.csv"
    p.write_text("t,lat,lon,alt,v_N,v_E,v_D,extra\n1,40.0,14.0,10,1,0,0,x\n0,40.1,14.1,11,0,1,0,y\n")
    log = read_flight(p)
    np.testing.assert_array_equal(log.t, [0.0, 1.0])  # sorted by time
    np.testing.assert_array_equal(log.lat, [40.1, 40.0])
    p.write_text("t,lat,lon,alt,v_N,v_E,v_D\n0,40.0,14.0,10,1,0,nan\n1,40.0,14.0,10,1,0,0\n")
    with pytest.raises(DataFormatError, match=r"line 2, column 'v_D': non-finite value"):
        read_flight(p)
    p.write_text("t,lat,lon\n0,1,2\n")
    with pytest.raises(DataFormatError, match=r"line 1: missing column"):
        read_flight(p)
