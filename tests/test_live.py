"""Live telemetry on loopback: ``uasnav replay`` → ``uasnav monitor`` (F3548 conformance) and
``uasnav replay`` → ``uasnav nav --live`` (= ``nav --causal``), over real UDP sockets between
processes that the tests start and that stop by themselves (``--idle-exit``,
``--exit-when-ended``)."""

from __future__ import annotations

import json
import socket
import subprocess
from datetime import datetime, timezone

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.web.process import uasnav_command

TLOG = "flights/phoenix_mission1_arducopter.tlog"
LOG171 = "logs/ardupilot_log171.bin"
#: The tlog's second flight (log seconds after its first message): armed at 289 s, disarmed at 362 s.
RUN = (280.0, 372.0)
SPEED = 20.0


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def run_pair(receiver: list[str], sender: list[str], timeout: float = 90.0) -> tuple[str, str]:
    """Start the receiver, then the sender; both end by themselves. Returns the receiver's
    stdout and stderr."""
    rx = subprocess.Popen(
        [*uasnav_command(), *receiver], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        import time

        time.sleep(1.5)  # the receiver binds its socket
        tx = subprocess.run([*uasnav_command(), *sender], capture_output=True, text=True, timeout=timeout)
        assert tx.returncode == 0, tx.stderr
        out, err = rx.communicate(timeout=timeout)
    finally:
        if rx.poll() is None:
            rx.kill()
            rx.wait()
    assert rx.returncode == 0, err
    return out, err


@pytest.fixture(scope="module")
def flown(shared_data):
    """From the tlog's own runs: the UTC of the second flight's arming, and the climb and
    descent speeds the runs achieved from arming to the take-off waypoint and from the last
    waypoint to disarming (m/s; ArduCopter slows its landing near the ground)."""
    from pymavlink import mavutil

    m = mavutil.mavlink_connection(str(shared_data / TLOG), dialect="ardupilotmega")
    t0 = offset = None
    armed = False
    arms: list[tuple[float, float]] = []  # (log s, boot s)
    climbs, descents, last_wp = [], [], None
    boot = 0.0
    clock: list[tuple[float, float]] = []  # (log s, boot s)
    while True:
        msg = m.recv_match(type=["SYSTEM_TIME", "HEARTBEAT", "MISSION_ITEM_REACHED"])
        if msg is None:
            break
        t0 = t0 if t0 is not None else msg._timestamp
        t = msg._timestamp - t0
        if msg.get_type() == "SYSTEM_TIME":
            boot = msg.time_boot_ms * 1e-3
            clock.append((t, boot))
            if msg.time_unix_usec:
                offset = msg.time_unix_usec * 1e-6 - boot
        elif msg.get_type() == "HEARTBEAT" and msg.get_srcSystem() == 1:
            now = bool(msg.base_mode & 128)
            if now and not armed:
                arms.append((t, boot))
            elif armed and not now and last_wp is not None:
                descents.append(t - last_wp)
                last_wp = None
            armed = now
        elif msg.get_type() == "MISSION_ITEM_REACHED" and arms:
            if msg.seq == 1:
                climbs.append(t - arms[-1][0])
            elif msg.seq == 3:
                last_wp = t
    second = next(b for t, b in arms if t > RUN[0])
    alt = 20.0  # the plan's take-off and waypoint altitude above home
    return {
        "utc": datetime.fromtimestamp(offset + second, timezone.utc),
        "climb_ms": alt / float(np.mean(climbs)),
        "descent_ms": alt / float(np.mean(descents)),
        "boot_at": lambda log_s: float(np.interp(log_s, *np.array(clock).T)),
    }


@pytest.fixture(scope="module")
def intent(shared_data, flown, tmp_path_factory):
    """An intent for the tlog's plan departing at the second flight's arming, from a model
    trained on the tlog's own runs (its autopilot limits and speed), with the climb and descent
    speeds its runs achieved. The plan's first waypoint
    lies 2.8 m from home (shorter than a predictor segment, which ``trajectory intent``
    refuses): it is left out, the take-off climb covers it."""
    import dataclasses

    from uasnav.io.plans import read_plan, write_plan

    d = tmp_path_factory.mktemp("live")
    model, out, plan = d / "model.json", d / "phoenix.json", d / "phoenix.plan"
    tlog = str(shared_data / TLOG)
    p = read_plan(tlog)
    write_plan(dataclasses.replace(p, items=(p.items[0], *p.items[2:])), plan)
    r = CliRunner().invoke(main, ["trajectory", "train", tlog, "--out", str(model)])
    assert r.exit_code == 0, r.output
    start = flown["utc"].isoformat().replace("+00:00", "Z")
    r = CliRunner().invoke(
        main,
        ["trajectory", "intent", "--model", str(model), "--plan", str(plan), "--wind", "0@0",
         "--start", start, "--limits-from", tlog, "--climb-rate", f"{flown['climb_ms']:.3f}",
         "--descent-rate", f"{flown['descent_ms']:.3f}", "--calibration-runs", "20", "--out", str(out)],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    return out


def monitor_events(shared_data, intent, *replay_args: str, monitor_args: tuple[str, ...] = ()) -> list[dict]:
    port = free_udp_port()
    out, _ = run_pair(
        ["monitor", f"udpin:127.0.0.1:{port}", "--intent", str(intent), "--json-lines", "--idle-exit", "2",
         "--exit-when-ended", *monitor_args],
        ["replay", str(shared_data / TLOG), "--to", f"udp:127.0.0.1:{port}", "--speed", str(SPEED),
         "--from", str(RUN[0]), *replay_args],
    )  # fmt: skip
    return [json.loads(line) for line in out.splitlines() if line.strip()]


def states(events: list[dict]) -> list[str]:
    return [e["state"] for e in events if e["event"] == "state"]


def test_replayed_flight_stays_activated_and_ends_on_landing(shared_data, intent):
    ev = monitor_events(shared_data, intent, "--stop-after", str(RUN[1]))
    assert states(ev) == ["Accepted", "Activated", "Ended"], ev
    act = next(e for e in ev if e["state"] == "Activated")
    assert act["margin_m"] > 0 and act["volume"] == 0
    # each event on a message carries its latency (measured, not asserted: see BENCHMARKS.md)
    assert all(e["latency_ms"] >= 0 for e in ev if e["event"] == "state" and e["state"] != "Accepted")


def test_offset_goes_nonconforming_and_back(shared_data, intent, flown):
    # 100 m east from 30 s into the window (after take-off) for 20 s: outside, back, Ended
    t_on, t_off = RUN[0] + 30, RUN[0] + 50
    ev = monitor_events(
        shared_data, intent, "--stop-after", str(RUN[1]), "--offset-after", f"{t_on}:0,100",
        "--offset-until", str(t_off),
    )  # fmt: skip
    assert states(ev) == ["Accepted", "Activated", "Nonconforming", "Activated", "Ended"], ev
    nc = next(e for e in ev if e["state"] == "Nonconforming")
    assert nc["margin_m"] < 0 and "horizontally" in nc["reason"]
    # judged at the first report after the shift: within one report interval (≈ 1 s, vehicle time)
    assert 0 <= nc["time_boot_s"] - flown["boot_at"](t_on) <= 1.0
    back = [e for e in ev if e["state"] == "Activated"][1]
    assert 0 <= back["time_boot_s"] - flown["boot_at"](t_off) <= 1.0
    assert back["reason"] == "back inside the intent" and back["margin_m"] > 0


def test_cut_stream_gives_telemetry_loss_then_contingent(shared_data, intent):
    ev = monitor_events(
        shared_data, intent, "--stop-after", str(RUN[0] + 40),
        monitor_args=("--telemetry-timeout", "3", "--contingent-after-loss", "6", "--idle-exit", "1.5"),
    )  # fmt: skip
    kinds = [e["event"] if e["event"] != "state" else e["state"] for e in ev]
    assert "telemetry_lost" in kinds and kinds[-1] == "Contingent", kinds
    assert kinds.index("telemetry_lost") < kinds.index("Contingent")
    assert "telemetry lost" in ev[-1]["reason"]


def test_loss_and_duplication_are_absorbed(shared_data, intent):
    ev = monitor_events(
        shared_data, intent, "--stop-after", str(RUN[1]), "--drop", "0.1", "--duplicate", "0.3", "--seed", "3"
    )
    assert states(ev) == ["Accepted", "Activated", "Ended"], ev


def test_nav_live_equals_causal_bit_for_bit(shared_data, tmp_path):
    log = str(shared_data / LOG171)
    causal = tmp_path / "causal.csv"
    r = CliRunner().invoke(main, ["nav", "--causal", log, "--out", str(causal)])
    assert r.exit_code == 0, r.output
    port = free_udp_port()
    live = tmp_path / "live.csv"
    _, err = run_pair(
        ["nav", "--live", f"udpin:127.0.0.1:{port}", "--out", str(live), "--idle-exit", "2"],
        ["replay", log, "--to", f"udp:127.0.0.1:{port}", "--speed", "10", "--stop-after", "60"],
        timeout=120,
    )
    a = np.loadtxt(live, delimiter=",", skiprows=1)
    b = np.loadtxt(causal, delimiter=",", skiprows=1)
    assert a.shape[0] > 1000 and "0 refused" in err
    # the live run saw the first 60 s: every row it has equals the causal run's row exactly
    assert np.array_equal(a, b[: a.shape[0]])
    assert live.read_text().splitlines()[:50] == causal.read_text().splitlines()[:50]


def test_replay_converts_dataflash_to_ground_station_messages(shared_data):
    import itertools

    from uasnav.live.source import log_packets

    pk = list(itertools.islice(log_packets(shared_data / LOG171), 4000))
    types = {p.msg.get_type() for p in pk}
    assert {"RAW_IMU", "HEARTBEAT", "SYSTEM_TIME", "GPS_RAW_INT", "GLOBAL_POSITION_INT"} <= types
    imu_t = np.array([p.t_s for p in pk if p.msg.get_type() == "RAW_IMU"])
    assert np.median(np.diff(imu_t)) == pytest.approx(0.02, abs=0.002)  # the logged 50 Hz
    assert all(np.diff([p.t_s for p in pk]) >= 0)
    # every message encodes (MAVLink 2) and decodes back to itself (floats as float32)
    from uasnav.live.source import mavlink_dialect

    mav = mavlink_dialect().MAVLink(None, srcSystem=1, srcComponent=1)
    for p in pk[:300]:
        back = mav.decode(bytearray(p.msg.pack(mav))).to_dict()
        for k, v in p.msg.to_dict().items():
            assert back[k] == (pytest.approx(v, rel=1e-6, abs=1e-30) if isinstance(v, float) else v)


def test_bad_input_is_one_error_line(tmp_path):
    r = CliRunner().invoke(main, ["replay", str(tmp_path / "x.csv"), "--to", "udp:127.0.0.1:9"])
    assert r.exit_code == 1 and "cannot replay .csv" in r.output
    r = CliRunner().invoke(main, ["replay", str(tmp_path / "x.tlog"), "--to", "tcp:x"])
    assert r.exit_code == 1 and "--to: expected udp:HOST:PORT" in r.output
    r = CliRunner().invoke(main, ["monitor", "bogus", "--intent", str(tmp_path / "none.json")])
    assert r.exit_code == 1 and "error:" in r.output
    r = CliRunner().invoke(main, ["nav", "--causal"])
    assert r.exit_code == 2 and "--causal needs LOG" in r.output


def test_live_page_shows_the_state_change_in_chromium(shared_data, intent, monkeypatch):
    import shutil
    import time

    from playwright.sync_api import expect, sync_playwright

    from uasnav.web.process import running_server

    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    assert chromium, "chromium is not installed: run `make setup`"
    port = free_udp_port()
    monkeypatch.setenv("UASNAV_LIVE_CONNECTION", f"udpin:127.0.0.1:{port}")
    monkeypatch.setenv("UASNAV_LIVE_INTENTS", str(intent))
    with running_server() as server, sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium)
        try:
            page = browser.new_page()
            page.set_default_timeout(60_000)
            outside: list[str] = []
            page.route(
                "**/*",
                lambda r: (
                    r.continue_()
                    if r.request.url.startswith(server.url)
                    else (outside.append(r.request.url), r.abort())
                ),
            )
            page.goto(server.url + "/live")
            page.wait_for_selector("#live-map polygon")  # the intent's volumes, drawn offline
            time.sleep(1.0)  # the page's first request started the receiver
            tx = subprocess.Popen(
                [*uasnav_command(), "replay", str(shared_data / TLOG), "--to", f"udp:127.0.0.1:{port}",
                 "--speed", str(SPEED), "--from", str(RUN[0]), "--stop-after", str(RUN[1])],
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            )  # fmt: skip
            try:
                cell = "#live-vehicles tbody tr[data-vehicle='1'] td:nth-child(2)"
                expect(page.locator(cell)).to_have_text("Activated", timeout=60_000)
                # snapshots arrive at ≥ 5 Hz
                n = page.evaluate(
                    "() => new Promise(done => { let n = 0; const s = new EventSource('/live/events');"
                    " s.onmessage = () => n++; setTimeout(() => { s.close(); done(n); }, 2000); })"
                )
                assert n >= 10, n
                expect(page.locator(cell)).to_have_text("Ended", timeout=60_000)
                assert "Ended" in page.inner_text("#live-events")
                assert page.locator("#veh-1").count() == 1
            finally:
                tx.wait(timeout=60)
        finally:
            browser.close()
    assert outside == []
