"""uasnav.fleet on a real Dask LocalCluster (2 worker processes, one per module): the cluster's
output equals the single-process path's, bit for bit; resume does only what is missing; corrupt
logs become rows of the errors table; killing a worker that runs a task does not change the
output (each log exactly once)."""

from __future__ import annotations

import json
import os
import shutil
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav import fleet
from uasnav.cli import main
from uasnav.errors import InputError
from uasnav.fleet.anomaly import robust_z
from uasnav.fleet.output import MANIFEST, read_dataset, read_errors
from uasnav.fleet.simulate import load_truth


@pytest.fixture(scope="module")
def worker_tmp(tmp_path_factory):
    """The workers' temporary folder: their own (TMPDIR when they start), so that a check for
    leftovers there is not disturbed by other processes using the machine's."""
    return tmp_path_factory.mktemp("worker-tmp")


@pytest.fixture(scope="module")
def client(worker_tmp):
    from distributed import Client

    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("TMPDIR", str(worker_tmp))
        cluster = fleet.local_cluster(2)
        c = Client(cluster)
        yield c
        c.close()
        cluster.close()


@pytest.fixture(scope="module")
def fleet_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("fleet")
    fleet.simulate_fleet(d, vehicles=3, flights=2, seed=3, duration_s=40.0)
    return d


@pytest.fixture(scope="module")
def reference(fleet_dir, tmp_path_factory):
    """The single-process outputs (workers=0) of both analyses."""
    out = tmp_path_factory.mktemp("ref")
    res = {}
    for a in (fleet.IMU_HEALTH, fleet.SCAN):
        s = fleet.run(a, [fleet_dir], out / f"{a.name}.parquet", workers=0)
        res[a.name] = (s, read_dataset(s.out), read_errors(s.out))
    return res


def _same(out, ref):
    _, rows, errors = ref
    got = read_dataset(out)
    assert got.num_rows == rows.num_rows > 0
    assert got.equals(rows), "cluster output differs from the single-process output"
    assert read_errors(out).equals(errors)
    assert len(set(got.column("log_hash").to_pylist())) == len(
        {(h) for h in rows.column("log_hash").to_pylist()}
    )


def test_simulated_fleet_truth(fleet_dir, reference):
    truth = load_truth(fleet_dir)
    assert len(truth.files) == 3 * 2 + 1 and len(truth.corrupt) == 1 and len(truth.faulty) == 1
    s, rows, errors = reference["imu_health"]
    assert (s.n_logs, s.n_ok, s.n_errors, s.n_rows) == (7, 6, 1, 6)
    # the corrupt file is in the errors table with the reader's message, the rest complete
    assert errors.column("path").to_pylist() == [str(fleet_dir / truth.corrupt[0])]
    assert "line" in errors.column("error")[0].as_py()
    # the white noise read from the static part is the simulated one: the faulty IMU's is ×8
    faulty = str(fleet_dir / truth.faulty[0])
    paths = rows.column("path").to_pylist()
    arw = np.array(rows.column("gyro_random_walk_x").to_pylist())
    models = rows.column("imu_model").to_pylist()
    i = paths.index(faulty)
    peers = [k for k in range(len(paths)) if models[k] == models[i] and k != i]
    assert arw[i] > 4 * max(arw[peers])
    # partitions: vehicle and day from the logs' own metadata
    assert set(rows.column("vehicle").to_pylist()) == {"V01", "V02", "V03"}
    assert all(d.startswith("2026-11-0") for d in rows.column("day").to_pylist())


def test_health_numbers_match_the_simulated_sensor(tmp_path):
    """The noise terms are uasnav.allan/noise's on the static part: the simulator's white noise."""
    from uasnav.fleet.imu_health import imu_health_of
    from uasnav.sim import load_preset, simulate

    log = simulate("lsm6dsm", duration=60.0, rate=100.0, seed=5)
    row = imu_health_of(log)
    white = load_preset("lsm6dsm").gyro.white  # rad/s/√Hz = rad/√s
    for a in "xyz":
        assert row[f"gyro_random_walk_{a}"] == pytest.approx(white, rel=0.15)
    assert row["static_s"] == pytest.approx(60.0, abs=0.5)
    # the long-τ terms of a one-minute static log are null with a reason, never a guess
    assert row["gyro_rate_ramp"] is None and row["gyro_rate_ramp_reason"]
    bias = log.truth["gyro_bias"].mean(axis=0)
    for i, a in enumerate("xyz"):
        assert row[f"gyro_bias_{a}"] == pytest.approx(bias[i], abs=2e-3)  # plus noise, Earth rate


def test_anomaly_score_finds_the_faulty_imus(client, tmp_path):
    """5 vehicles × 4 flights: the outliers are exactly the generator's faulty IMUs."""
    src = tmp_path / "fleet"
    fleet.simulate_fleet(src, vehicles=5, flights=4, seed=11, duration_s=30.0, corrupt=False)
    s = fleet.run(fleet.IMU_HEALTH, [src], tmp_path / "h.parquet", client=client)
    truth = load_truth(src)
    found = sorted(Path(o["path"]).relative_to(src).as_posix() for o in s.extra["outliers"])
    assert found == sorted(truth.faulty) and len(found) == 2
    scores = fleet.read_scores(s.out)
    assert scores.num_rows == 20 and all(v is not None for v in scores.column("score").to_pylist())


def test_robust_z_is_the_modified_z_score():
    x = np.array([1.0, 2.0, 3.0, 4.0, 100.0, 5.0])
    g = np.array(["a"] * 6)
    z, ok = robust_z(x, g)
    med, mad = 3.5, 1.5  # median of the six; median |x − 3.5| = 1.5
    assert np.allclose(z, 0.6745 * (x - med) / mad) and ok.all()
    z2, ok2 = robust_z(x[:4], g[:4])  # fewer than 5: no score
    assert np.isnan(z2).all() and not ok2.any()


def test_cluster_equals_single_process(client, fleet_dir, reference, tmp_path):
    for a in (fleet.IMU_HEALTH, fleet.SCAN):
        s = fleet.run(a, [fleet_dir], tmp_path / f"{a.name}.parquet", client=client)
        assert s.workers == 2 and s.scheduler.startswith("tcp://")
        _same(s.out, reference[a.name])
    assert fleet.read_scores(tmp_path / "imu_health.parquet").equals(
        fleet.read_scores(Path(reference["imu_health"][0].out))
    )


def test_resume_does_only_what_is_missing(client, fleet_dir, reference, tmp_path):
    src = tmp_path / "src"
    shutil.copytree(fleet_dir, src)
    late = sorted(src.glob("V03/*.csv"))
    held = tmp_path / "held"
    held.mkdir()
    for f in late:
        f.rename(held / f.name)
    out = tmp_path / "h.parquet"
    first = fleet.run(fleet.IMU_HEALTH, [src], out, client=client)
    assert first.n_logs == 5
    with pytest.raises(InputError, match="--resume"):
        fleet.run(fleet.IMU_HEALTH, [src], out, client=client)
    for f in late:
        (held / f.name).rename(src / "V03" / f.name)
    again = fleet.run(fleet.IMU_HEALTH, [src], out, client=client, resume=True)
    assert (again.n_logs, again.n_skipped, again.n_ok + again.n_errors) == (7, 5, 2)
    # the same rows as one run over everything (paths differ: compare without them)
    ref = reference["imu_health"][1].drop_columns(["path"])
    assert read_dataset(out).drop_columns(["path"]).equals(ref)
    nothing = fleet.run(fleet.IMU_HEALTH, [src], out, client=client, resume=True)
    assert (nothing.n_skipped, nothing.n_ok, nothing.n_errors) == (7, 0, 0)
    lines = (out / MANIFEST).read_text().splitlines()
    assert len(lines) == 7 and len({json.loads(x)["path"] for x in lines}) == 7
    # a copy of a finished log under a new name: recognised by its content, stored once
    shutil.copy(src / "V01" / "flight_001.csv", src / "V01" / "copy.csv")
    copy = fleet.run(fleet.IMU_HEALTH, [src], out, client=client, resume=True)
    assert (copy.n_skipped, copy.n_ok, copy.n_rows) == (7, 1, 1)
    assert read_dataset(out).drop_columns(["path"]).equals(ref)


def test_torn_manifest_line_is_ignored(fleet_dir, tmp_path):
    out = tmp_path / "s.parquet"
    calls = []
    fleet.run(fleet.SCAN, [fleet_dir], out, workers=0, progress=lambda d, n: calls.append((d, n)))
    assert calls[0] == (0, 7) and calls[-1] == (7, 7) and len(calls) == 8
    with open(out / MANIFEST, "a") as fh:
        fh.write('{"path": "/x", "si')  # a client killed while appending
    s = fleet.run(fleet.SCAN, [fleet_dir], out, workers=0, resume=True)
    assert (s.n_skipped, s.n_ok) == (7, 0)


def test_scan_inventory_of_real_logs(shared_data, tmp_path):
    logs = [
        shared_data / "logs" / "px4_sample_log_small.ulg",
        shared_data / "logs" / "ardupilot_log171.bin",
        shared_data / "flights" / "phoenix_mission1_arducopter.tlog",
    ]
    s = fleet.run(fleet.SCAN, logs, tmp_path / "scan.parquet", workers=0)
    assert s.n_errors == 0, s.errors
    rows = {Path(r["path"]).name: r for r in read_dataset(s.out).to_pylist()}
    bin_ = rows["ardupilot_log171.bin"]
    assert bin_["format"] == "ardupilot-dataflash" and bin_["n_imus"] == 3
    imu3 = next(i for i in bin_["imus"] if i["name"] == "IMU3")
    assert imu3["temp_min_c"] == pytest.approx(25.5, abs=0.6) and imu3["temp_max_c"] == pytest.approx(
        42.0, abs=0.6
    )
    tlog = rows["phoenix_mission1_arducopter.tlog"]
    assert tlog["gnss"] and tlog["mission"] and tlog["n_waypoints"] >= 2
    assert tlog["day"] == "2018-09-17"  # the ground station's clock (the file is named 2018-09-17 16-44-06)
    ulg = rows["px4_sample_log_small.ulg"]
    assert ulg["autopilot"] == "PX4" and ulg["gnss"] and not ulg["mission"]
    # the flight controller's UUID is the vehicle (and the partition)
    assert ulg["vehicle_id"] == ulg["vehicle"] == "000600000000383638393239510d0035002d"
    assert all(len(r["log_hash"]) == 64 for r in rows.values())
    # the ULog's GNSS UTC time dates it; its three sensor_gyro/sensor_accel instances are listed
    assert ulg["day"] == "2021-04-21"
    assert [i["name"] for i in ulg["imus"]] == ["sensor_combined"] + [f"sensor_imu[{k}]" for k in range(3)]
    # the DataFlash board identity line is the vehicle; GPS week/time of week date it
    assert bin_["vehicle_id"] == "PX4v2 004A002F 33345119 32383433"
    assert bin_["vehicle"] == "PX4v2_004A002F_33345119_32383433"  # partition names: no spaces
    assert bin_["day"] == "2015-11-21"


def test_ulog_instances_and_start_against_pyulog(shared_data):
    import datetime as dt

    from pyulog import ULog

    from uasnav.io.formats.ulog import read_ulog_imus

    path = shared_data / "logs" / "px4_sample_log_small.ulg"
    imus = read_ulog_imus(path)
    u = ULog(str(path))
    for k in range(3):
        g = next(d for d in u.data_list if d.name == "sensor_gyro" and d.multi_id == k)
        a = next(d for d in u.data_list if d.name == "sensor_accel" and d.multi_id == k)
        log = imus[f"sensor_imu[{k}]"]
        i = np.searchsorted(g.data["timestamp"], log.t[0] * 1e6 - 0.5)
        n = log.n
        np.testing.assert_array_equal(log.gyro[:, 0], g.data["x"][i : i + n])
        np.testing.assert_array_equal(log.temp, g.data["temperature"][i : i + n])
        # accelerometer linearly interpolated to the gyro's instants
        ta, tg = a.data["timestamp"] * 1e-6, g.data["timestamp"][i : i + n] * 1e-6
        np.testing.assert_allclose(log.accel[:, 2], np.interp(tg, ta, a.data["z"]), rtol=1e-6)
    gps = next(d for d in u.data_list if d.name == "vehicle_gps_position")
    start = dt.datetime.fromisoformat(imus["sensor_combined"].meta["start_time"])
    expect = (gps.data["time_utc_usec"][0] - (gps.data["timestamp"][0] - u.start_timestamp)) * 1e-6
    assert start.timestamp() == pytest.approx(expect, abs=1e-3)


def test_dataflash_identity_closed_form(shared_data):
    import datetime as dt

    from uasnav.io.formats.dataflash import read_dataflash_identity

    ident = read_dataflash_identity(shared_data / "logs" / "ardupilot_log171.bin")
    assert ident["vehicle"] == "PX4v2 004A002F 33345119 32383433"
    # first 3-D fix: GPS week 1871, 603 882.4 s of week, boot time T = 45.136 s; GPS − UTC = 17 s
    gps = dt.datetime(1980, 1, 6, tzinfo=dt.timezone.utc) + dt.timedelta(weeks=1871, seconds=603_882.4)
    assert ident["boot_utc"] == gps - dt.timedelta(seconds=17 + 45.136)


def test_imu_health_of_real_logs(shared_data, tmp_path):
    logs = [shared_data / "logs" / "ardupilot_log171.bin", shared_data / "logs" / "px4_sample.ulg"]
    s = fleet.run(fleet.IMU_HEALTH, logs, tmp_path / "h.parquet", workers=0)
    assert (s.n_ok, s.n_errors, s.n_rows) == (2, 0, 4)
    rows = {r["imu"]: r for r in read_dataset(s.out).to_pylist()}
    assert set(rows) == {"IMU", "IMU2", "IMU3", "sensor_combined"}
    for r in rows.values():
        assert r["static_s"] >= 10.0 and r["noise_reason"] is None
        assert all(r[f"gyro_random_walk_{a}"] > 0 for a in "xyz")
        # a static minute shows white noise only: the longest-τ term is null with the reason
        assert r["gyro_rate_ramp"] is None and r["gyro_rate_ramp_reason"]
        assert all(r[f"vibration_{a}"] > 0 for a in "xyz")
    # IMU3 warms by 16 °C: its slope is measured; the others warm < 2 °C while static
    assert rows["IMU3"]["gyro_temp_slope_x"] is not None and rows["IMU3"]["temp_slope_reason"] is None
    assert rows["IMU"]["gyro_temp_slope_x"] is None and "°C" in rows["IMU"]["temp_slope_reason"]
    assert rows["sensor_combined"]["temp_slope_reason"] == "no temperature channel"


def test_cli_scheduler_file_and_address(client, fleet_dir, reference, tmp_path):
    sched = tmp_path / "scheduler.json"
    # what `dask scheduler --scheduler-file` writes, reduced to what a client reads (Client.
    # write_scheduler_file dumps scheduler_info(), which after a run may hold tuple keys JSON refuses)
    sched.write_text(json.dumps({"type": "Scheduler", "address": client.scheduler.address}))
    out = tmp_path / "scan.parquet"
    r = CliRunner().invoke(
        main, ["fleet", "scan", str(fleet_dir), "--out", str(out), "--scheduler-file", str(sched), "--json"]
    )
    assert r.exit_code == 0, r.output
    info = json.loads(r.stdout)
    assert (info["logs"], info["ok"], info["errors"], info["workers"]) == (7, 6, 1, 2)
    _same(out, reference["scan"])
    out2 = tmp_path / "h.parquet"
    html = tmp_path / "fleet.html"
    r = CliRunner().invoke(
        main,
        ["fleet", "imu-health", str(fleet_dir), "--out", str(out2), "--scheduler", client.scheduler.address,
         "--report", str(html)],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    assert "1 error(s)" in r.stdout
    _same(out2, reference["imu_health"])
    page = html.read_text()
    assert "Outliers" in page and "broken_001.csv" in page and "data:image/png;base64," in page


def test_health_report_of_a_fleet_without_a_readable_log(fleet_dir, tmp_path):
    from uasnav.fleet.html import render_health_report

    out = tmp_path / "h.parquet"
    s = fleet.run(fleet.IMU_HEALTH, [fleet_dir / "corrupt"], out, workers=0)
    assert (s.n_ok, s.n_errors, s.extra["n_imus"]) == (0, 1, 0)
    page = render_health_report(out)
    assert "0 IMU(s)" in page and "1 unreadable" in page


def test_cli_errors(fleet_dir, tmp_path):
    run = CliRunner().invoke
    r = run(main, ["fleet", "scan", str(fleet_dir), "--out", str(tmp_path / "x.csv"), "--workers", "0"])
    assert r.exit_code == 1 and "expected a name ending in .parquet" in r.stderr
    r = run(
        main,
        ["fleet", "scan", str(tmp_path / "nope"), "--out", str(tmp_path / "x.parquet"), "--workers", "0"],
    )
    assert r.exit_code == 1 and "no such file" in r.stderr and not (tmp_path / "x.parquet").exists()
    r = run(
        main, ["fleet", "scan", str(fleet_dir), "--out", str(tmp_path / "x.parquet"), "--scheduler", "nohost"]
    )
    assert r.exit_code == 2 and "--scheduler" in r.stderr
    r = run(main, ["fleet", "simulate", "--vehicles", "1", "--flights", "1", "--out", str(fleet_dir)])
    assert r.exit_code == 1 and "not empty" in r.stderr


def test_cli_simulate_then_scan_in_process(tmp_path):
    d = tmp_path / "f"
    r = CliRunner().invoke(main, ["fleet", "simulate", "--vehicles", "2", "--flights", "1", "--out", str(d),
                                  "--duration", "5", "--json"])  # fmt: skip
    assert r.exit_code == 0, r.output
    info = json.loads(r.stdout)
    assert info["files"] == 3 and len(info["faulty"]) == 1 and len(info["corrupt"]) == 1
    r = CliRunner().invoke(
        main, ["fleet", "scan", str(d), "--out", str(tmp_path / "s.parquet"), "--workers", "0"]
    )
    assert r.exit_code == 0, r.output
    rows = read_dataset(tmp_path / "s.parquet")
    assert sorted(rows.column("duration_s").to_pylist()) == pytest.approx([4.99, 4.99])


def _executing(dask_worker):  # runs on each worker
    return len(dask_worker.state.executing)


def test_killed_worker_mid_run(client, fleet_dir, reference, tmp_path):
    """SIGKILL the worker process that runs a task: Dask re-runs the task elsewhere, the output
    equals the single-process output and each log is there exactly once."""
    out = tmp_path / "h.parquet"
    result: dict[str, object] = {}

    def go():
        try:
            result["summary"] = fleet.run(fleet.IMU_HEALTH, [fleet_dir], out, client=client)
        except BaseException as e:  # pragma: no cover - reported below
            result["error"] = e

    pids = client.run(os.getpid)
    th = threading.Thread(target=go)
    th.start()
    killed = None
    deadline = time.monotonic() + 60
    while killed is None and time.monotonic() < deadline and th.is_alive():
        busy = client.run(_executing)
        for addr, n in busy.items():
            if n > 0 and addr in pids:
                os.kill(pids[addr], signal.SIGKILL)
                killed = addr
                break
        time.sleep(0.05)
    th.join(180)
    assert killed is not None, "no worker was seen running a task"
    assert "error" not in result, result.get("error")
    s = result["summary"]
    assert (s.n_logs, s.n_ok, s.n_errors) == (7, 6, 1)
    _same(out, reference["imu_health"])
    lines = (out / MANIFEST).read_text().splitlines()
    assert sorted(json.loads(x)["path"] for x in lines) == sorted({json.loads(x)["path"] for x in lines})
    client.wait_for_workers(2, timeout=60)
    assert set(client.run(os.getpid).values()) != set(pids.values())  # a new process took over


def test_elements_dataset_trains_the_same_model(client, shared_data, fleet_dir, tmp_path):
    """`fleet elements` on the cluster = the single-process rows = flight_samples' elements; and
    `uasnav trajectory train ELEMENTS.parquet` trains the model training on the log gives."""
    from uasnav.fleet.elements import ELEMENTS
    from uasnav.trajectory.element_table import read_element_dataset
    from uasnav.trajectory.flights import flight_samples

    tlog = shared_data / "flights" / "phoenix_mission1_arducopter.tlog"
    one = fleet.run(ELEMENTS, [tlog, fleet_dir], tmp_path / "e1.parquet", workers=0)
    two = fleet.run(ELEMENTS, [tlog, fleet_dir], tmp_path / "e2.parquet", client=client)
    assert (one.n_ok, one.n_empty, one.n_errors) == (1, 7, 0)  # IMU-only logs: no mission
    assert read_dataset(two.out).equals(read_dataset(one.out))
    samples, seg, runs = read_element_dataset(one.out)
    ref = flight_samples([tlog])
    assert (seg, runs, len(samples)) == (10.0, len(ref), ref.n_elements)
    r = ref.concat()
    for name in ("t_real_s", "dv_ms", "v_init_ms", "length_m", "flight", "element"):
        assert np.array_equal(getattr(samples, name), getattr(r, name)), name
    assert np.array_equal(samples.features.theta_deg, r.features.theta_deg)
    m1, m2 = tmp_path / "m1.json", tmp_path / "m2.json"
    for src, m in ((str(tlog), m1), (one.out, m2)):
        # the LVQ model (its network is trained on the elements alone; the default kinematic
        # model also keeps the log's autopilot limits, which an element dataset does not carry)
        res = CliRunner().invoke(
            main, ["trajectory", "train", src, "--method", "lvq", "--out", str(m), "--json"]
        )
        assert res.exit_code == 0, res.output
        assert json.loads(res.stdout)["n_runs"] == len(ref)
    a, b = json.loads(m1.read_text()), json.loads(m2.read_text())
    assert a == b and a["count_table"] and a["lvq"]
    res = CliRunner().invoke(main, ["trajectory", "train", one.out, "--out", str(m2), "--segment", "5"])
    assert res.exit_code == 1 and "10 m segments" in res.stderr
    # other measuring options go to the workers with the analysis
    e5 = tmp_path / "e5.parquet"
    res = CliRunner().invoke(main, ["fleet", "elements", str(tlog), "--out", str(e5), "--segment", "5",
                                    "--scheduler", client.scheduler.address])  # fmt: skip
    assert res.exit_code == 0, res.output
    s5, seg5, _ = read_element_dataset(e5)
    assert seg5 == 5.0 and len(s5) == flight_samples([tlog], segment_m=5.0).n_elements


@pytest.fixture(scope="module")
def nav_fleet(tmp_path_factory):
    """2 vehicles × (1 IMU-only log + 1 GNSS/INS flight of 130 s: .csv + _gnss.csv + .tlog)."""
    d = tmp_path_factory.mktemp("navfleet")
    fleet.simulate_fleet(
        d, vehicles=2, flights=1, seed=5, duration_s=20.0, corrupt=False, nav_flights=1, nav_duration_s=130.0
    )
    return d


def test_simulated_flights_carry_gnss_and_mission(client, nav_fleet, tmp_path):
    from uasnav.fleet.elements import ELEMENTS
    from uasnav.io import read_flight

    truth = load_truth(nav_fleet)
    assert sorted(f.file for f in truth.files if "nav_" in f.file) == [
        f"V0{v}/nav_001{ext}" for v in (1, 2) for ext in (".csv", ".tlog", "_gnss.csv")
    ]
    s = fleet.run(fleet.SCAN, [nav_fleet], tmp_path / "scan.parquet", workers=0)
    rows = {Path(r["path"]).relative_to(nav_fleet).as_posix(): r for r in read_dataset(s.out).to_pylist()}
    # the GNSS CSV is part of its IMU log, not a log of its own
    assert sorted(rows) == [
        f"V0{v}/{n}" for v in (1, 2) for n in ("flight_001.csv", "nav_001.csv", "nav_001.tlog")
    ]
    for v in ("V01", "V02"):
        imu_only, nav_csv, tlog = (
            rows[f"{v}/flight_001.csv"],
            rows[f"{v}/nav_001.csv"],
            rows[f"{v}/nav_001.tlog"],
        )
        assert (imu_only["gnss"], imu_only["mission"]) == (False, False)
        assert (nav_csv["format"], nav_csv["gnss"], nav_csv["mission"], nav_csv["vehicle"]) == (
            "csv-v1",
            True,
            False,
            v,
        )
        assert nav_csv["duration_s"] == pytest.approx(130.0, abs=0.02)
        assert (tlog["format"], tlog["gnss"], tlog["mission"], tlog["n_waypoints"], tlog["n_imus"]) == (
            "mavlink-tlog", True, True, 4, 0,
        )  # fmt: skip
        assert tlog["day"] == nav_csv["day"]  # the telemetry's wall clock is the flight's start
        # the telemetry is the true track: the waypoints lie on it, reached lap after lap in order
        fl = read_flight(nav_fleet / v / "nav_001.tlog")
        assert fl.cruise_ms == 8.0
        seqs = [q for _, q in fl.reached]
        assert seqs[:5] == [5, 2, 3, 4, 5]  # top of the climb (last waypoint), then the circuit
        for t_r, q in fl.reached:
            k = int(np.argmin(np.abs(fl.t - t_r)))
            lat, lon, _ = fl.waypoints[q]
            assert abs(fl.lat[k] - lat) < 3e-5 and abs(fl.lon[k] - lon) < 4e-5  # within ~3 m
    el = fleet.run(ELEMENTS, [nav_fleet], tmp_path / "el.parquet", client=client)
    t = read_dataset(el.out)
    assert el.n_errors == 0 and t.num_rows > 20
    assert {Path(p).name for p in t.column("path").to_pylist()} == {"nav_001.tlog"}
    single = fleet.run(ELEMENTS, [nav_fleet], tmp_path / "el1.parquet", workers=0)
    assert read_dataset(single.out).equals(t)


def test_fleet_nav_cluster_equals_single_process(client, nav_fleet, shared_data, tmp_path):
    from uasnav.fleet.nav import NAV

    ulg = shared_data / "logs" / "px4_sample_log_small.ulg"
    s1 = fleet.run(NAV, [nav_fleet, ulg], tmp_path / "nav1.parquet", workers=0)
    s2 = fleet.run(NAV, [nav_fleet, ulg], tmp_path / "nav2.parquet", client=client)
    one, two = read_dataset(s1.out), read_dataset(s2.out)
    assert one.num_rows == 3 and two.equals(one)
    assert read_errors(s2.out).equals(read_errors(s1.out)) and s1.n_errors == 0
    # IMU-only logs and telemetry-only logs give no row
    assert (s1.n_ok, s1.n_empty) == (3, 4)
    rows = {Path(r["path"]).name + r["vehicle"]: r for r in one.to_pylist()}
    for v in ("V01", "V02"):
        r = rows["nav_001.csv" + v]
        assert (r["reference"], r["outage_against"], r["gnss_fixes"]) == ("truth", "truth", 651)
        # GNSS σ is 1.5 m horizontally: the filter's solution is better than a fix
        assert 0.05 < r["horizontal_rms_m"] < 1.5 and r["velocity_rms_m_s"] < 0.5
        assert [r[f"outage_{d}s_n"] for d in (10, 30, 60)] == [3, 3, 3]
        # drift grows with the outage (MEMS IMU: metres after 10 s, tens to hundreds after 60 s)
        assert 0.2 < r["outage_10s_m"] < r["outage_30s_m"] < r["outage_60s_m"] < 2000.0
    u = next(r for r in one.to_pylist() if r["path"].endswith(".ulg"))
    assert u["reference"].startswith("PX4 EKF2") and u["outage_10s_n"] == 0 and u["outage_10s_m"] is None
    # the same replay as `uasnav nav` (one filter, one comparison)
    res = CliRunner().invoke(main, ["nav", str(ulg), "--json"])
    assert res.exit_code == 0, res.output
    ref = json.loads(res.output)["reference"]
    assert (
        u["horizontal_rms_m"] == ref["horizontal_rms_m"] and u["velocity_rms_m_s"] == ref["velocity_rms_m_s"]
    )


def test_cli_fleet_nav_and_simulate_nav_flights(tmp_path):
    d = tmp_path / "f"
    res = CliRunner().invoke(
        main,
        ["fleet", "simulate", "--vehicles", "1", "--flights", "1", "--nav-flights", "1", "--duration", "10",
         "--out", str(d), "--json"],
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    assert json.loads(res.output)["files"] == 5  # 1 IMU log, 1 corrupt, the flight's 3 files
    res = CliRunner().invoke(
        main,
        ["fleet", "nav", str(d / "V01"), "--out", str(tmp_path / "nav.parquet"), "--workers", "0", "--json"],
    )
    assert res.exit_code == 0, res.output
    info = json.loads(res.output)
    assert (info["logs"], info["ok"], info["rows"], info["errors"]) == (3, 1, 1, 0)


# --- logs named by http(s) URLs: each worker downloads its own log ---------------------------

_SLOW_S = 20.0  # how long /slow.csv drips (the runs below give up after 2 s)


@pytest.fixture(scope="module")
def log_server(fleet_dir):
    """A real HTTP server on loopback serving the simulated fleet, plus broken URLs: /slow.csv
    drips one byte per 0.2 s, /huge.csv streams 8 MB without Content-Length, /moved.csv
    redirects to a file:// URL; anything else missing is a 404. Records every GET."""
    from functools import partial
    from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer

    stop = threading.Event()
    requested: list[str] = []

    class Handler(SimpleHTTPRequestHandler):
        def log_message(self, *args):  # quiet
            pass

        def do_GET(self):
            requested.append(self.path)
            if self.path == "/slow.csv":
                self.send_response(200)
                self.send_header("Content-Length", "1000")
                self.end_headers()
                t0 = time.monotonic()
                while not stop.is_set() and time.monotonic() - t0 < _SLOW_S:
                    try:
                        self.wfile.write(b"#")
                        self.wfile.flush()
                    except OSError:
                        return
                    stop.wait(0.2)
            elif self.path == "/huge.csv":
                self.send_response(200)
                self.end_headers()  # no Content-Length: the size is found while reading
                try:
                    for _ in range(8):
                        self.wfile.write(b"0" * (1 << 20))
                except OSError:
                    pass
                self.close_connection = True
            elif self.path == "/moved.csv":
                self.send_response(302)
                self.send_header("Location", "file:///etc/passwd")
                self.end_headers()
            else:
                super().do_GET()

    server = ThreadingHTTPServer(("127.0.0.1", 0), partial(Handler, directory=str(fleet_dir)))
    server.daemon_threads = True
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}", requested
    stop.set()
    server.shutdown()
    server.server_close()


def _url_list(path, base, fleet_dir, logs, broken=()):
    lines = ["# a fleet's logs on a web server"] + [
        f"{base}/{Path(p).relative_to(fleet_dir).as_posix()}" for p in logs
    ]
    path.write_text("\n".join([*lines, *(f"{base}/{b}" for b in broken)]) + "\n")
    return path


_BROKEN = ("missing.csv", "slow.csv", "huge.csv", "moved.csv")


def _check_broken(errors, base):
    by_path = dict(zip(errors.column("path").to_pylist(), errors.column("error").to_pylist(), strict=True))
    kinds = dict(zip(errors.column("path").to_pylist(), errors.column("error_type").to_pylist(), strict=True))
    assert "HTTP 404" in by_path[f"{base}/missing.csv"]
    assert "timeout of 2 s" in by_path[f"{base}/slow.csv"]
    assert "size limit of 4194304 bytes" in by_path[f"{base}/huge.csv"]
    assert "redirect to 'file:///etc/passwd' refused" in by_path[f"{base}/moved.csv"]
    assert all(kinds[f"{base}/{b}"] == "FetchError" for b in _BROKEN)


def test_url_list_equals_the_logs_read_from_disk(
    client, worker_tmp, log_server, fleet_dir, reference, tmp_path
):
    """A .urls list of http:// logs on the 2-worker cluster: the same rows and hashes as the
    logs read from disk, the corrupt log and every broken URL in the errors table (with the URL
    and the reason), temporary downloads removed; --resume fetches only what is missing."""
    import tempfile

    # the downloads go to the workers' own temporary folder, checked for leftovers at the end
    assert set(client.run(tempfile.gettempdir).values()) == {str(worker_tmp)}
    base, requested = log_server
    _, ref_rows, ref_errors = reference["imu_health"]
    logs = sorted({*ref_rows.column("path").to_pylist(), *ref_errors.column("path").to_pylist()})
    assert len(logs) == 7
    url_of = {p: f"{base}/{Path(p).relative_to(fleet_dir).as_posix()}" for p in logs}
    fetch = {"fetch_timeout_s": 2.0, "fetch_max_bytes": 4 << 20}
    assert max(os.path.getsize(p) for p in logs) < 4 << 20
    tmp0 = set(worker_tmp.glob("uasnav-fleet-*"))

    # first run: 3 of the logs and the broken URLs
    out = tmp_path / "h.parquet"
    first = fleet.run(
        fleet.IMU_HEALTH, [_url_list(tmp_path / "a.urls", base, fleet_dir, logs[:3], _BROKEN)], out,
        client=client, **fetch,
    )  # fmt: skip
    assert (first.n_logs, first.n_errors) == (7, 4 + (ref_errors.column("path")[0].as_py() in logs[:3]))
    _check_broken(read_errors(out), base)
    # resume with the whole list: the 3 finished URLs are not fetched again, the broken ones are
    # tried again (a URL may come back), the 4 others are fetched once each
    requested.clear()
    full = _url_list(tmp_path / "all.urls", base, fleet_dir, logs, _BROKEN)
    again = fleet.run(fleet.IMU_HEALTH, [full], out, client=client, resume=True, **fetch)
    assert (again.n_logs, again.n_skipped) == (11, 3)
    got_paths = sorted(requested)
    assert got_paths == sorted([f"/{b}" for b in _BROKEN] + [url_of[p][len(base) :] for p in logs[3:]])

    rows = read_dataset(out)
    # the same numbers and content hashes as from disk; the path column names the URL
    assert rows.drop_columns(["path"]).equals(ref_rows.drop_columns(["path"]))
    assert rows.column("path").to_pylist() == [url_of[p] for p in ref_rows.column("path").to_pylist()]
    errors = read_errors(out)
    _check_broken(errors, base)
    bad = url_of[ref_errors.column("path")[0].as_py()]
    bad_row = errors.filter(pa_compute_equal(errors, "path", bad))
    assert bad_row.num_rows == 1
    assert bad_row.column("error")[0].as_py() == ref_errors.column("error")[0].as_py().replace(
        ref_errors.column("path")[0].as_py(), bad
    )
    assert bad_row.column("log_hash").equals(ref_errors.column("log_hash"))
    assert errors.num_rows == 5
    assert (
        fleet.read_scores(out)
        .drop_columns(["path"])
        .equals(fleet.read_scores(Path(reference["imu_health"][0].out)).drop_columns(["path"]))
    )
    # the manifest holds each URL once, by content hash; the broken ones are not in it
    entries = [json.loads(x) for x in (out / MANIFEST).read_text().splitlines()]
    assert sorted(e["path"] for e in entries) == sorted(url_of.values())
    assert {e["log_hash"] for e in entries} == {
        *ref_rows.column("log_hash").to_pylist(),
        *ref_errors.column("log_hash").to_pylist(),
    }
    # a rerun fetches only the broken URLs again; nothing left in the workers' temporary folder
    requested.clear()
    nothing = fleet.run(fleet.IMU_HEALTH, [full], out, client=client, resume=True, **fetch)
    assert (nothing.n_skipped, nothing.n_ok, nothing.n_errors) == (7, 0, 4)
    assert sorted(requested) == sorted(f"/{b}" for b in _BROKEN)
    assert set(worker_tmp.glob("uasnav-fleet-*")) == tmp0


def pa_compute_equal(table, column, value):
    import pyarrow.compute as pc

    return pc.equal(table.column(column), value)


def test_url_sources_in_process_and_cli(log_server, fleet_dir, reference, tmp_path):
    """The single-process path and the CLI take the same URL lists; other schemes are refused."""
    base, _ = log_server
    _, ref_rows, _ = reference["scan"]
    logs = sorted(ref_rows.column("path").to_pylist())[:2]
    lst = _url_list(tmp_path / "two.list", base, fleet_dir, logs, ["missing.csv"])
    r = CliRunner().invoke(
        main, ["fleet", "scan", str(lst), "--out", str(tmp_path / "s.parquet"), "--workers", "0", "--json"]
    )
    assert r.exit_code == 0, r.output
    summary = json.loads(r.stdout)
    assert (summary["logs"], summary["ok"], summary["errors"]) == (3, 2, 1)
    assert "HTTP 404" in summary["error_list"][0]["error"]
    rows = read_dataset(tmp_path / "s.parquet")
    want = ref_rows.filter(pa_compute_equal(ref_rows, "path", logs[0])).drop_columns(["path"])
    got = rows.filter(pa_compute_equal(rows, "log_hash", want.column("log_hash")[0])).drop_columns(["path"])
    assert got.equals(want)
    (tmp_path / "s3.urls").write_text("s3://bucket/log.ulg\n")
    with pytest.raises(InputError, match="s3:// URLs are not supported"):
        fleet.run(fleet.SCAN, [tmp_path / "s3.urls"], tmp_path / "x.parquet", workers=0)


def test_cli_memory_limit_of_the_local_workers(fleet_dir, tmp_path):
    run = CliRunner().invoke
    out = tmp_path / "s.parquet"
    r = run(
        main,
        ["fleet", "scan", str(fleet_dir / "V01"), "--out", str(out), "--workers", "1",
         "--memory-limit", "700M", "--json"],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    info = json.loads(r.stdout)
    assert (info["workers"], info["worker_memory_limit"], info["ok"]) == (1, 700 * 1024**2, 2)
    for argv, msg in (
        (["--memory-limit", "1G", "--workers", "0"], "local cluster"),
        (["--memory-limit", "lots"], "--memory-limit"),
        (["--memory-limit", "1k"], "at least 64M"),
    ):
        r = run(main, ["fleet", "scan", str(fleet_dir), "--out", str(tmp_path / "x.parquet"), *argv])
        assert r.exit_code == 2 and msg in r.stderr, r.output
