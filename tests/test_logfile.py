"""open_log: one decoding pass per command, typed views with units/frames/datums, and the
vertical comparison with the autopilot's estimate in one datum."""

from __future__ import annotations

import collections
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.errors import DataFormatError
from uasnav.geo.datum import HeightDatum, receiver_undulation
from uasnav.io import open_log
from uasnav.io.flight import BaroData, Flight, GnssData, MagData, Trajectory
from uasnav.io.mission_plan import MissionPlan
from uasnav.io.views import Identity, ModeTimeline


@pytest.fixture
def parses(monkeypatch: pytest.MonkeyPatch) -> collections.Counter[str]:
    """Counts decoding passes per file: pyulog.ULog constructions and pymavlink connections."""
    import pyulog
    from pymavlink import mavutil

    counts: collections.Counter[str] = collections.Counter()
    real_ulog = pyulog.ULog

    class CountingULog(real_ulog):  # type: ignore[misc, valid-type]
        def __init__(self, log_file: Any, *a: Any, **k: Any) -> None:
            counts[Path(str(log_file)).name] += 1
            super().__init__(log_file, *a, **k)

    real_conn = mavutil.mavlink_connection

    def counting_conn(device: Any, *a: Any, **k: Any) -> Any:
        counts[Path(str(device)).name] += 1
        return real_conn(device, *a, **k)

    monkeypatch.setattr(pyulog, "ULog", CountingULog)
    monkeypatch.setattr(mavutil, "mavlink_connection", counting_conn)
    # text logs: every numeric CSV is read by the CSV engine (NumericCsv.open), or as a whole
    # text when its header lies beyond the first chunk (read_text)
    from uasnav.io import _csvstream, _text

    real_open = _csvstream.NumericCsv.open.__func__  # type: ignore[attr-defined]

    def counting_open(cls: Any, path: Any) -> Any:
        counts[Path(str(path)).name] += 1
        return real_open(cls, path)

    real_text = _text.read_text

    def counting_text(path: Any) -> str:
        counts[Path(str(path)).name] += 1
        return real_text(path)

    monkeypatch.setattr(_csvstream.NumericCsv, "open", classmethod(counting_open))
    monkeypatch.setattr(_text, "read_text", counting_text)
    monkeypatch.setattr(_csvstream, "read_text", counting_text)
    return counts


def _run(args: list[str]) -> Any:
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0, r.output
    return r


@pytest.mark.parametrize(
    "args",
    [
        ["allan", "{ulg}", "--json"],
        ["zupt", "{ulg}", "--json"],
        ["nav", "{ulg}", "--json"],
        ["nav", "{tlog}", "--json"],
        ["trajectory", "evaluate", "{tlog}", "--json"],
        ["nav", "{bin}", "--json", "--end", "60"],
        ["allan", "{bin}", "--json"],
        ["calibrate", "{ulg}", "--method", "poly", "--out", "{tmp}/m.json"],
        ["replay", "{ulg}", "--to", "udp:127.0.0.1:9", "--speed", "1000", "--stop-after", "5"],
        ["allan", "{csv}", "--json"],
        ["zupt", "{csv}", "--json"],
        ["calibrate", "{csv}", "--method", "poly", "--out", "{tmp}/m.json"],
        ["calibrate", "--model", "{tmp}/m.json", "--test", "{csv}", "--json"],
        ["nav", "{csv}", "--gnss", "{gnss}", "--json"],
        ["allan", "{xio}", "--json"],
    ],
)
def test_each_command_decodes_a_log_once(
    shared_data: Path, parses: collections.Counter[str], args: list[str], tmp_path: Path
) -> None:
    from uasnav import sim
    from uasnav.io import write_log
    from uasnav.io.formats.gnss_csv import write_gnss_csv
    from uasnav.sim.flight import imu_log_with_truth, simulate_flight

    ulg = shared_data / "logs" / "px4_sample_log_small.ulg"
    tlog = shared_data / "flights" / "phoenix_mission1_arducopter.tlog"
    binlog = shared_data / "logs" / "ardupilot_log171.bin"
    xio = shared_data / "imu" / "xio_fusion_sensor_data.csv"
    csv, gnss = tmp_path / "imu.csv", tmp_path / "imu_gnss.csv"
    if "{gnss}" in args:
        f = simulate_flight(duration_s=60.0, seed=3)
        write_log(imu_log_with_truth(f), csv)
        write_gnss_csv(gnss, f.gnss)
    else:
        log = sim.simulate("ax1", profile="cycles", duration=300.0, rate=20.0, seed=1)
        write_log(log, csv)
        if "--model" in args:
            _run(["calibrate", str(csv), "--method", "poly", "--out", str(tmp_path / "m.json")])
    argv = [a.format(ulg=ulg, tlog=tlog, bin=binlog, csv=csv, gnss=gnss, xio=xio, tmp=tmp_path) for a in args]
    parses.clear()
    CliRunner().invoke(main, argv)  # the count matters, not the outcome on this sample
    name = Path(next(a for a in argv[1:] if a.startswith("/") and not a.endswith("m.json"))).name
    assert parses[name] == 1, dict(parses)
    if "{gnss}" in args:
        assert parses[gnss.name] == 1, dict(parses)


def test_train_intent_and_fleet_decode_a_log_once(
    shared_data: Path, parses: collections.Counter[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    tlog = shared_data / "flights" / "phoenix_mission1_arducopter.tlog"
    model = tmp_path / "m.json"
    _run(["trajectory", "train", str(tlog), "--method", "kinematic", "--out", str(model)])
    assert parses[tlog.name] == 1, dict(parses)
    parses.clear()
    plan = shared_data / "missions" / "mavsdk_qgroundcontrol_sample.plan"
    _run(
        ["trajectory", "intent", "--model", str(model), "--plan", str(plan), "--wind", "0@0",
         "--start", "2026-05-01T09:30:00Z", "--geoid-height", "47", "--limits-from", str(tlog),
         "--out", str(tmp_path / "intent.json")],
    )  # fmt: skip
    assert parses[tlog.name] == 1, dict(parses)
    ulg = shared_data / "logs" / "px4_sample_log_small.ulg"
    (tmp_path / "logs").mkdir()
    (tmp_path / "logs" / ulg.name).symlink_to(ulg)
    (tmp_path / "logs" / tlog.name).symlink_to(tlog)
    # the counters live in this process: analyse here, not in the per-log deadline's child
    import uasnav.fleet.runner as runner

    monkeypatch.setattr(runner, "call_with_deadline", lambda fn, arg, seconds, imports=(): fn(arg))
    for sub in ("scan", "imu-health", "elements", "nav"):
        parses.clear()
        out = tmp_path / f"{sub}.parquet"
        CliRunner().invoke(main, ["fleet", sub, str(tmp_path / "logs"), "--out", str(out), "--workers", "0"])
        want = {ulg.name: 1, tlog.name: 1}
        assert {k: parses[k] for k in want} == want, (sub, dict(parses))


def test_declared_views_share_one_pass(shared_data: Path, parses: collections.Counter[str]) -> None:
    p = shared_data / "flights" / "phoenix_mission1_arducopter.tlog"
    log = open_log(p, need={"imus", "nav", "flight", "plan", "params", "limits", "modes", "identity"})
    for v in (
        "imus",
        "gnss",
        "baro",
        "autopilot_estimate",
        "flight",
        "plan",
        "params",
        "limits",
        "modes",
        "identity",
    ):
        log.view(v)
    assert parses[p.name] == 1
    log.view("gnss")  # cached
    assert parses[p.name] == 1


def _check_views(log: Any, gnss_datum: HeightDatum) -> None:
    imus = log.imus
    assert imus and all(m.t.size >= 2 and m.gyro.shape[1] == 3 for m in imus.values())
    g = log.gnss
    assert isinstance(g, GnssData) and g.alt_datum is gnss_datum and np.all(np.abs(g.lat) <= 90)
    assert isinstance(log.baro, BaroData) and isinstance(log.mag, MagData)
    est = log.autopilot_estimate
    # the estimate is given in the fixes' datum: the heights compare directly
    assert isinstance(est, Trajectory) and est.alt_datum is g.alt_datum
    assert isinstance(log.flight, Flight) and log.flight.alt_datum is HeightDatum.AMSL
    assert isinstance(log.params, dict) and len(log.params) > 10
    assert isinstance(log.modes, ModeTimeline) and len(log.modes.names) >= 1
    assert isinstance(log.identity, Identity) and log.identity.autopilot


def test_views_of_the_shared_ulog(shared_data: Path) -> None:
    log = open_log(
        shared_data / "flights" / "px4_s500_mission_land.ulg",
        need={"imus", "nav", "flight", "plan", "params", "modes", "identity"},
    )
    _check_views(log, HeightDatum.ELLIPSOID)
    assert isinstance(log.plan, MissionPlan) and log.plan.items
    g = log.gnss
    # the receiver's own undulation (alt_ellipsoid − alt) at the flight site
    assert g.geoid_undulation_m == pytest.approx(-34.665, abs=0.01)
    ident = log.identity
    assert (
        ident.autopilot == "PX4"
        and ident.firmware_version.startswith("1.11.0")
        and ident.board == "PX4_FMU_V5"
    )
    assert ident.date is not None and ident.date.year == 2021
    assert "AUTO_MISSION" in log.modes.names
    assert log.limits.climb_ms is not None


def test_views_of_the_shared_tlog(shared_data: Path) -> None:
    log = open_log(shared_data / "flights" / "phoenix_mission1_arducopter.tlog")
    _check_views(log, HeightDatum.AMSL)  # GPS_RAW_INT.alt / GLOBAL_POSITION_INT.alt, both AMSL
    assert isinstance(log.plan, MissionPlan)
    assert log.identity.clock == "wall" and log.identity.autopilot == "ArduPilot"
    assert {"AUTO", "STABILIZE"} <= set(log.modes.names)


def test_views_of_the_shared_dataflash(shared_data: Path) -> None:
    log = open_log(
        shared_data / "logs" / "ardupilot_log171.bin",
        need={"imus", "nav", "flight", "params", "modes", "identity"},
    )
    _check_views(log, HeightDatum.AMSL)  # GPS.Alt is AMSL, the EKF's origin too
    ident = log.identity
    assert ident.vehicle_type == "ArduCopter" and ident.firmware_version.startswith("3.3")
    assert ident.leap_seconds == 17 and ident.utc_at_zero is not None and ident.utc_at_zero.year == 2015
    assert log.modes.names[0] == "LOITER"


def test_receiver_undulation() -> None:
    assert receiver_undulation([10.0, 11.0], [44.0, 45.0]) == -34.0
    with pytest.raises(Exception, match="both"):
        receiver_undulation([math.nan], [1.0])


def test_px4_vertical_agrees_with_ekf2(shared_data: Path) -> None:
    r = _run(["nav", str(shared_data / "flights" / "px4_s500_mission_land.ulg"), "--json"])
    ref = json.loads(r.output)["reference"]
    assert ref["datum"] == "ellipsoid"
    assert ref["vertical_rms_m"] <= 3.0 and ref["horizontal_rms_m"] <= 1.0


def _ulog_amsl_origin(path: Path, undulation: float) -> None:
    from ulog_writer import write_ulog

    imu_f = (
        (("uint64_t", "timestamp"),)
        + tuple(("float", f"gyro_rad[{i}]") for i in range(3))
        + tuple(("float", f"accelerometer_m_s2[{i}]") for i in range(3))
    )
    imu = [
        {"timestamp": int(1e6 + k * 1e4), **{f"gyro_rad[{i}]": 0.0 for i in range(3)},
         "accelerometer_m_s2[0]": 0.0, "accelerometer_m_s2[1]": 0.0, "accelerometer_m_s2[2]": -9.80}
        for k in range(6000)
    ]  # fmt: skip
    amsl = 400.0
    gps_f = (("uint64_t", "timestamp"), ("uint8_t", "fix_type"), ("int32_t", "lat"), ("int32_t", "lon"),
             ("int32_t", "alt"), ("int32_t", "alt_ellipsoid"), ("float", "vel_n_m_s"), ("float", "vel_e_m_s"),
             ("float", "vel_d_m_s"), ("float", "eph"), ("float", "epv"),
             ("float", "s_variance_m_s"))  # fmt: skip
    gps = [
        {"timestamp": int(1e6 + k * 2e5), "fix_type": 3, "lat": 473977000, "lon": 85456000,
         "alt": int(amsl * 1e3), "alt_ellipsoid": int((amsl + undulation) * 1e3), "vel_n_m_s": 0.0,
         "vel_e_m_s": 0.0, "vel_d_m_s": 0.0, "eph": 1.0, "epv": 1.5, "s_variance_m_s": 0.2}
        for k in range(300)
    ]  # fmt: skip
    lp_f = (("uint64_t", "timestamp"), ("double", "ref_lat"), ("double", "ref_lon"), ("float", "ref_alt"),
            *(("float", c) for c in ("x", "y", "z", "vx", "vy", "vz")))  # fmt: skip
    lp = [
        {"timestamp": int(1e6 + k * 1e5), "ref_lat": 47.3977, "ref_lon": 8.5456, "ref_alt": amsl,
         **{c: 0.0 for c in ("x", "y", "z", "vx", "vy", "vz")}}
        for k in range(600)
    ]  # fmt: skip
    write_ulog(
        path,
        {
            "sensor_combined": (imu_f, imu),
            "vehicle_gps_position": (gps_f, gps),
            "vehicle_local_position": (lp_f, lp),
        },
    )


def test_written_ulog_with_an_amsl_ekf2_origin(tmp_path: Path) -> None:
    p = tmp_path / "amsl_origin.ulg"
    _ulog_amsl_origin(p, undulation=47.0)
    log = open_log(p)
    assert log.gnss.alt_datum is HeightDatum.ELLIPSOID and log.gnss.alt[0] == pytest.approx(447.0)
    est = log.autopilot_estimate
    assert est.alt_datum is HeightDatum.ELLIPSOID and est.alt[0] == pytest.approx(447.0, abs=1e-3)
    r = _run(["nav", str(p), "--json"])
    ref = json.loads(r.output)["reference"]
    assert ref["datum"] == "ellipsoid" and ref["vertical_rms_m"] <= 3.0


def test_open_log_by_url(shared_data: Path, tmp_path: Path) -> None:
    import functools
    import http.server
    import shutil
    import threading

    shutil.copy(shared_data / "logs" / "px4_sample_log_small.ulg", tmp_path / "x.ulg")

    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *a: Any) -> None:
            """No access log on stderr."""

    handler = functools.partial(Quiet, directory=str(tmp_path))
    srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    try:
        log = open_log(f"http://127.0.0.1:{srv.server_address[1]}/x.ulg")
        assert log.format_name == "px4-ulog" and log.imu.n > 100
        direct = open_log(tmp_path / "x.ulg").imu
        assert np.array_equal(log.imu.gyro, direct.gyro)
    finally:
        srv.shutdown()


def test_a_gnss_csv_replaces_the_logs_fixes(shared_data: Path, tmp_path: Path) -> None:
    from uasnav.io.formats.gnss_csv import write_gnss_csv

    p = shared_data / "flights" / "px4_s500_mission_land.ulg"
    own = open_log(p).gnss
    fixes = own.select(np.arange(own.n) % 2 == 0)
    write_gnss_csv(tmp_path / "g.csv", fixes)
    nav = open_log(p, gnss=str(tmp_path / "g.csv")).nav
    assert nav.gnss.n == fixes.n and nav.imu.n > 1000
    with pytest.raises(DataFormatError, match="carries no plan"):
        open_log(shared_data / "imu" / "xio_fusion_sensor_data.csv").view("plan")


def test_format_classes_state_their_interface() -> None:
    from uasnav.io.formats.alfa import AlfaFormat
    from uasnav.io.formats.base import ImuFileFormat, LogFormat, WholeFileFormat
    from uasnav.io.logfile import _CSV, BY_EXTENSION

    with pytest.raises(TypeError, match="abstract"):
        LogFormat(Path("x"))  # type: ignore[abstract]

    class NoReader(ImuFileFormat):
        name = "no-reader"

    with pytest.raises(TypeError, match="read_imu"):
        NoReader(Path("x"))  # type: ignore[abstract]

    class NoIdentity(WholeFileFormat):
        name = "no-identity"

    with pytest.raises(TypeError, match="build_identity"):
        NoIdentity(Path("x"))  # type: ignore[abstract]
    for cls in (*BY_EXTENSION.values(), *_CSV.values(), AlfaFormat):
        fmt = cls(Path("x"))
        assert fmt.name and cls.carries("identity"), cls


def test_one_flight_model_for_the_filter_and_the_trajectory(shared_data: Path) -> None:
    """``nav`` and ``flight`` are the same type: the sensors and estimate of one, the logged
    track and mission events of the other; a flight without sensors is refused by the filter."""
    from uasnav import ins
    from uasnav.errors import InputError

    log = open_log(shared_data / "flights" / "px4_s500_mission_land.ulg", need={"nav", "flight"})
    nav, fl = log.nav, log.flight
    assert type(nav) is type(fl) is Flight
    assert nav.imu is not None and nav.gnss is not None and nav.track is None
    assert fl.imu is None and fl.track is not None and fl.reached
    assert fl.t is fl.track.t and fl.vel_ned.shape == (fl.t.size, 3)
    assert fl.alt_datum is fl.track.alt_datum is HeightDatum.AMSL
    assert nav.source == fl.source == str(log.path)
    with pytest.raises(InputError, match="no position telemetry"):
        _ = nav.t
    with pytest.raises(InputError, match="no imu and gnss"):
        ins.run(fl)
    # unsorted telemetry with a repeated stamp: sorted, the first sample of a stamp kept
    f = Flight.from_track([1.0, 0.0, 1.0], [45.0, 45.1, 45.2], [7.0] * 3, [1.0] * 3, np.zeros((3, 3)))
    assert f.t.tolist() == [0.0, 1.0] and f.lat.tolist() == [45.1, 45.0]
