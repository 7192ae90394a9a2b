"""Live telemetry on loopback: ``uasnav replay`` → ``uasnav monitor`` (F3548 conformance) and
``uasnav replay`` → ``uasnav nav --live`` (= ``nav --causal``), over real UDP and TCP sockets
between processes that the tests start and that stop by themselves (``--idle-exit``,
``--exit-when-ended``)."""

from __future__ import annotations

import json
import re
import socket
import subprocess
import time
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.web.process import uasnav_command

TLOG = "flights/phoenix_mission1_arducopter.tlog"
LOG171 = "logs/ardupilot_log171.bin"
#: The tlog's second flight (log seconds after its first message): armed at 289 s, disarmed at 362 s.
RUN = (280.0, 372.0)
#: Replay speed of the monitor scenarios: the monitor judges on vehicle time, so the outcome does
#: not depend on it; the scenarios run side by side.
SPEED = 40.0
#: Scenarios that are not about telemetry loss allow a long silence (vehicle s) before
#: Contingent: at SPEED a stall of the replaying process under load must not count as a C2 loss.
PATIENT = ("--contingent-after-loss", "60")


def free_port(kind: int = socket.SOCK_DGRAM) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def listening(port: int, proto: str) -> bool:
    """Whether a socket of this machine is bound to ``port`` (UDP) or listens on it (TCP), from
    ``/proc/net`` (probing by binding would race with the receiver's own bind)."""
    for table in (f"/proc/net/{proto}", f"/proc/net/{proto}6"):
        try:
            lines = Path(table).read_text().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            cols = line.split()
            if int(cols[1].rsplit(":", 1)[1], 16) == port and (proto == "udp" or cols[3] == "0A"):
                return True
    return False


@dataclass
class Pair:
    """A receiver and a sender process; :meth:`finish` waits for both to end by themselves."""

    rx: subprocess.Popen[str]
    tx: subprocess.Popen[str]

    def finish(self, timeout: float = 120.0) -> tuple[str, str, str]:
        """(receiver stdout, receiver stderr, sender stderr); both must exit 0."""
        try:
            _, tx_err = self.tx.communicate(timeout=timeout)
            out, err = self.rx.communicate(timeout=timeout)
        finally:
            for p in (self.rx, self.tx):
                if p.poll() is None:
                    p.kill()
                    p.wait()
        assert self.tx.returncode == 0, tx_err
        assert self.rx.returncode == 0, err
        return out, err, tx_err


def start_pair(receiver: list[str], sender: list[str], port: int, proto: str = "udp") -> Pair:
    """Start the receiver, wait until it is bound to ``port``, then start the sender."""
    rx = subprocess.Popen(
        [*uasnav_command(), *receiver], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    deadline = time.monotonic() + 60.0
    while not listening(port, proto):
        if rx.poll() is not None or time.monotonic() > deadline:
            rx.kill()
            _, err = rx.communicate()
            pytest.fail(f"the receiver did not bind {proto} port {port}: {err}")
        time.sleep(0.05)
    tx = subprocess.Popen(
        [*uasnav_command(), *sender], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    return Pair(rx, tx)


#: ArduCopter's AUTO in HEARTBEAT.custom_mode.
AUTO = 3


@pytest.fixture(scope="module")
def flown(shared_data):
    """From the tlog's own runs: the UTC at which the second flight's mission started (AUTO, the
    time the runs are measured from), and the climb and descent speeds the runs achieved from
    the mission's start to the take-off waypoint and from the last waypoint to disarming (m/s;
    ArduCopter slows its landing near the ground)."""
    from pymavlink import mavutil

    m = mavutil.mavlink_connection(str(shared_data / TLOG), dialect="ardupilotmega")
    t0 = offset = None
    armed = False
    starts: list[tuple[float, float]] = []  # (log s, boot s) of each mission start
    last_arm = -1.0
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
                last_arm = t
            if now and msg.custom_mode == AUTO and (not starts or starts[-1][0] < last_arm):
                starts.append((t, boot))
            if armed and not now and last_wp is not None:
                descents.append(t - last_wp)
                last_wp = None
            armed = now
        elif msg.get_type() == "MISSION_ITEM_REACHED" and starts:
            if msg.seq == 1:
                climbs.append(t - starts[-1][0])
            elif msg.seq == 3:
                last_wp = t
    second = next(b for t, b in starts if t > RUN[0])
    alt = 20.0  # the plan's take-off and waypoint altitude above home
    return {
        "utc": datetime.fromtimestamp(offset + second, timezone.utc),
        "climb_ms": alt / float(np.mean(climbs)),
        "descent_ms": alt / float(np.mean(descents)),
        "boot_at": lambda log_s: float(np.interp(log_s, *np.array(clock).T)),
    }


@pytest.fixture(scope="module")
def phoenix(shared_data, tmp_path_factory):
    """The tlog's whole plan (its first waypoint 2.8 m from home included: ``trajectory
    intent`` merges such short legs into their neighbours) and a model trained on the tlog's
    own runs (its autopilot limits and speed)."""
    from uasnav.io.plans import read_plan, write_plan

    d = tmp_path_factory.mktemp("live")
    model, plan = d / "model.json", d / "phoenix.plan"
    tlog = str(shared_data / TLOG)
    write_plan(read_plan(tlog), plan)
    r = CliRunner().invoke(main, ["trajectory", "train", tlog, "--out", str(model)])
    assert r.exit_code == 0, r.output
    return {"model": model, "plan": plan, "dir": d}


@pytest.fixture(scope="module")
def intent(shared_data, flown, phoenix):
    """An intent for the tlog's plan departing at the second flight's mission start, with the
    climb and descent speeds its runs achieved and time bounds from how this prediction missed
    the tlog's own five AUTO runs (``--flights``)."""
    out = phoenix["dir"] / "phoenix.json"
    tlog = str(shared_data / TLOG)
    start = flown["utc"].isoformat().replace("+00:00", "Z")
    r = CliRunner().invoke(
        main,
        ["trajectory", "intent", "--model", str(phoenix["model"]), "--plan", str(phoenix["plan"]),
         "--wind", "0@0", "--start", start, "--limits-from", tlog, "--climb-rate", f"{flown['climb_ms']:.3f}",
         "--descent-rate", f"{flown['descent_ms']:.3f}", "--flights", tlog, "--json", "--out", str(out)],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    source = json.loads(r.output)["time_bounds_source"]
    assert source.startswith("5 AUTO runs of the vehicle (phoenix_mission1_arducopter.tlog): Student-t"), (
        source
    )
    return out


#: name → (replay arguments, monitor arguments, transport); every scenario replays the tlog
#: from RUN[0].
SCENARIOS: dict[str, tuple[tuple[str, ...], tuple[str, ...], str]] = {
    "run": (("--stop-after", str(RUN[1])), PATIENT, "udp"),
    "offset": (
        ("--stop-after", str(RUN[1]), "--offset-after", f"{RUN[0] + 30}:0,100",
         "--offset-until", str(RUN[0] + 50)),
        (*PATIENT, "--exit-when-ended"),
        "udp",
    ),
    "cut": (
        ("--stop-after", str(RUN[0] + 40)),
        ("--telemetry-timeout", "10", "--contingent-after-loss", "20", "--idle-exit", "1.5"),
        "udp",
    ),
    "lossy": (
        ("--stop-after", str(RUN[1]), "--drop", "0.1", "--duplicate", "0.3", "--seed", "3"), PATIENT, "udp"
    ),
    "tcp": (("--stop-after", str(RUN[1])), PATIENT, "tcp"),
}  # fmt: skip


@dataclass
class Monitored:
    """One scenario's outcome: the monitor's events and closing line, the replay's line."""

    events: list[dict]
    summary: str
    sent: str


@pytest.fixture(scope="module")
def monitored(shared_data, intent) -> dict[str, Monitored]:
    """Every scenario of :data:`SCENARIOS`, replay → monitor over loopback, run side by side."""
    pairs = {}
    for name, (replay_args, monitor_args, proto) in SCENARIOS.items():
        port = free_port(socket.SOCK_STREAM if proto == "tcp" else socket.SOCK_DGRAM)
        listen, to = (f"tcpin:127.0.0.1:{port}", f"tcp:127.0.0.1:{port}") if proto == "tcp" else (
            f"udpin:127.0.0.1:{port}", f"udp:127.0.0.1:{port}"
        )  # fmt: skip
        pairs[name] = start_pair(
            ["monitor", listen, "--intent", str(intent), "--json-lines", "--idle-exit", "2", *monitor_args],
            ["replay", str(shared_data / TLOG), "--to", to, "--speed", str(SPEED), "--from", str(RUN[0]),
             *replay_args],
            port,
            proto,
        )  # fmt: skip
    out = {}
    for name, pair in pairs.items():
        stdout, err, sent = pair.finish()
        events = [json.loads(line) for line in stdout.splitlines() if line.strip()]
        out[name] = Monitored(events, err.strip().splitlines()[-1], sent.strip().splitlines()[-1])
    return out


def transitions(events: list[dict]) -> list[dict]:
    """The state changes among the events (every event carries the state it happened in)."""
    return [e for e in events if e["event"] == "state"]


def states(events: list[dict]) -> list[str]:
    return [e["state"] for e in transitions(events)]


def count(pattern: str, text: str) -> int:
    m = re.search(pattern, text)
    assert m, (pattern, text)
    return int(m.group(1))


def test_replayed_flight_stays_activated_and_ends_on_landing(monitored):
    ev = monitored["run"].events
    assert states(ev) == ["Accepted", "Activated", "Ended"], ev
    act = next(e for e in transitions(ev) if e["state"] == "Activated")
    assert act["margin_m"] > 0 and act["volume"] == 0
    # each event on a message carries its latency (measured, not asserted: see BENCHMARKS.md)
    assert all(e["latency_ms"] >= 0 for e in ev if e["event"] == "state" and e["state"] != "Accepted")


def test_every_flight_conforms_to_an_intent_from_its_other_runs(shared_data, flown, phoenix):
    """Held out in 4D: each of the tlog's five AUTO flights, its messages fed to the monitor
    offline, against an intent for its own mission start whose 95 % time bounds come from the
    other four runs only, stays Activated from arming (it waits on the pad before its first
    volume opens) and Ends."""
    from uasnav.io import open_log
    from uasnav.io.operational_intent import NamedIntent
    from uasnav.io.plans import read_plan
    from uasnav.live.conformance import ConformanceMonitor
    from uasnav.live.source import log_packets
    from uasnav.trajectory.mission_runs import MISSION_VIEWS
    from uasnav.trajectory.models import load_model
    from uasnav.trajectory.timebounds import PaceBounds
    from uasnav.utm.intent import build_intent, vehicle_run_bounds

    log = open_log(shared_data / TLOG, need=("limits", *MISSION_VIEWS))
    model, plan = load_model(phoenix["model"]), read_plan(phoenix["plan"])
    kw = {"climb_ms": flown["climb_ms"], "descent_ms": flown["descent_ms"],
          "accel_z_ms2": log.limits.accel_z_ms2, "cruise_ms": log.limits.cruise_ms}  # fmt: skip
    runs = list(vehicle_run_bounds([log], model, np.zeros(2), **kw).runs)
    packets = [p for p in log_packets(shared_data / TLOG) if p.msg.get_srcSystem() == 1]
    flights, armed, boot, to_unix, auto = [], False, 0.0, 0.0, None
    for k, p in enumerate(packets):  # (first packet, mission start UTC, last packet) of each flight
        m = p.msg
        boot = m.time_boot_ms * 1e-3 if getattr(m, "time_boot_ms", None) is not None else boot
        if m.get_type() == "SYSTEM_TIME" and m.time_unix_usec:
            to_unix = m.time_unix_usec * 1e-6 - boot
        if m.get_type() == "HEARTBEAT" and m.autopilot != 8:
            now = bool(m.base_mode & 128)
            if now and not armed:
                first, auto = max(k - 200, 0), None
            if now and m.custom_mode == AUTO and auto is None:
                auto = to_unix + boot
            if armed and not now and auto is not None:
                flights.append((first, auto, k + 1))
            armed = now
    assert len(flights) == len(runs) == 5
    for j, (a, start, b) in enumerate(flights):
        model.time_bounds_ = PaceBounds.of_runs([r for i, r in enumerate(runs) if i != j], 10.0, "four runs")
        built = build_intent(plan, model, np.zeros(2), datetime.fromtimestamp(start, timezone.utc), **kw)
        monitor = ConformanceMonitor([NamedIntent("phoenix", built.details)])
        events = [e for p in packets[a:b] for e in monitor.on_message(p.msg, p.t_s)]
        assert states(events) == ["Accepted", "Activated", "Ended"], (j, transitions(events))
        act = transitions(events)[1]
        assert act["reason"] == "armed" and act["volume"] == 0 and act["margin_m"] > 0


@pytest.fixture(scope="module")
def recorded_gaps(shared_data) -> int:
    """Gaps in the tlog's own MAVLink sequence numbers over the replayed window: packets its
    radio link lost when it was recorded."""
    from uasnav.live.source import log_packets

    last: dict[tuple[int, int], int] = {}
    gaps, t0 = 0, None
    for pk in log_packets(shared_data / TLOG):
        t0 = pk.t_s if t0 is None else t0
        if not RUN[0] <= pk.t_s - t0 <= RUN[1]:
            if pk.t_s - t0 > RUN[1]:
                break
            continue
        key, seq = (pk.msg.get_srcSystem(), pk.msg.get_srcComponent()), pk.msg.get_seq()
        if key in last and (seq - last[key] - 1) % 256 < 128:
            gaps += (seq - last[key] - 1) % 256
        last[key] = seq
    return gaps


@pytest.mark.parametrize("scenario", ["run", "tcp"])
def test_monitor_receives_every_packet_sent(monitored, recorded_gaps, scenario):
    """Every packet sent is received, or counted where this machine dropped it (UDP: a full
    kernel receive buffer); the losses by sequence number are the recording's own."""
    m = monitored[scenario]
    sent = count(r"sent (\d+) packets", m.sent)
    received = count(r"(\d+) messages received", m.summary)
    # the kernel's count is known for a UDP socket (Linux), not for a TCP stream
    kernel = count(r"(\d+) dropped by a full kernel receive buffer", m.summary) if scenario == "run" else 0
    queue = count(r"(\d+) dropped by a full queue", m.summary)
    assert received + kernel + queue == sent, (m.sent, m.summary)
    if scenario == "tcp":  # a stream: nothing can be lost on the way
        assert received == sent, m.summary
    if kernel == 0:
        assert count(r"(\d+) lost by sequence number", m.summary) == recorded_gaps > 0
    assert states(m.events) == ["Accepted", "Activated", "Ended"], m.events
    if scenario == "tcp":  # every report arrives: Ended at the first one on the ground, before disarming
        end = transitions(m.events)[-1]
        assert end["reason"].startswith("landed") and end["time_boot_s"] < 147.0, end


def test_offset_goes_nonconforming_and_back(monitored, flown):
    # 100 m east from 30 s into the window (after take-off) for 20 s: outside, back, Ended
    t_on, t_off = RUN[0] + 30, RUN[0] + 50
    ev = monitored["offset"].events
    assert states(ev) == ["Accepted", "Activated", "Nonconforming", "Activated", "Ended"], ev
    nc = next(e for e in transitions(ev) if e["state"] == "Nonconforming")
    assert nc["margin_m"] < 0 and "horizontally" in nc["reason"]
    # judged at the first report after the shift: within one report interval (≈ 1 s, vehicle time)
    assert 0 <= nc["time_boot_s"] - flown["boot_at"](t_on) <= 1.0
    back = [e for e in transitions(ev) if e["state"] == "Activated"][1]
    assert 0 <= back["time_boot_s"] - flown["boot_at"](t_off) <= 1.0
    assert back["reason"] == "back inside the intent" and back["margin_m"] > 0
    # --exit-when-ended stops at Ended, before the replay has sent its last packets
    s = monitored["offset"].summary
    assert s.endswith("stopped once every intent had Ended"), s
    assert count(r"(\d+) messages received", s) < count(r"sent (\d+) packets", monitored["offset"].sent)


def test_cut_stream_gives_telemetry_loss_then_contingent(monitored):
    ev = monitored["cut"].events
    kinds = [e["event"] if e["event"] != "state" else e["state"] for e in ev]
    assert "telemetry_lost" in kinds and kinds[-1] == "Contingent", kinds
    assert kinds.index("telemetry_lost") < kinds.index("Contingent")
    assert "telemetry lost" in ev[-1]["reason"]


def test_loss_and_duplication_are_absorbed(monitored):
    m = monitored["lossy"]
    assert states(m.events) == ["Accepted", "Activated", "Ended"], m.events
    assert count(r"(\d+) dropped, ", m.sent) > 0 and count(r"(\d+) duplicated;", m.sent) > 0
    assert count(r"\((\d+) duplicated/late skipped", m.summary) > 0


def test_replay_tcpin_serves_the_first_receiver(shared_data):
    """``--to tcpin:`` waits for a receiver to connect, then streams the packets whole."""
    port = free_port(socket.SOCK_STREAM)
    tx = subprocess.Popen(
        [*uasnav_command(), "replay", str(shared_data / TLOG), "--to", f"tcpin:127.0.0.1:{port}",
         "--speed", "100", "--from", str(RUN[0]), "--stop-after", str(RUN[0] + 10)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 60.0
        while not listening(port, "tcp"):
            assert tx.poll() is None and time.monotonic() < deadline, tx.stderr.read() if tx.stderr else ""
            time.sleep(0.05)
        data = bytearray()
        with socket.create_connection(("127.0.0.1", port), timeout=60) as s:
            while chunk := s.recv(65536):
                data += chunk
        _, err = tx.communicate(timeout=60)
    finally:
        if tx.poll() is None:
            tx.kill()
            tx.wait()
    assert tx.returncode == 0, err
    assert "waiting up to 30 s for a receiver" in err
    from uasnav.live.source import mavlink_dialect

    mav = mavlink_dialect().MAVLink(None)
    mav.robust_parsing = True
    msgs = [m for m in mav.parse_buffer(bytes(data)) or [] if m.get_type() != "BAD_DATA"]
    sent = count(r"sent (\d+) packets", err)
    assert len(msgs) == sent > 100 and count(r"\((\d+) bytes", err) == len(data)


def _packets(n: int) -> bytes:
    """``n`` HEARTBEAT + GLOBAL_POSITION_INT pairs from vehicle 1 as bytes on the wire."""
    from uasnav.live.source import mavlink_dialect

    d = mavlink_dialect()
    mav = d.MAVLink(None, srcSystem=1, srcComponent=1)
    out = bytearray()
    for k in range(n):
        out += mav.heartbeat_encode(2, 3, 0, 0, 4).pack(mav)
        pos = mav.global_position_int_encode(1000 * k, 492574131, -1232431096, 92000, 0, 0, 0, 0, 0)
        out += pos.pack(mav)
    return bytes(out)


@pytest.mark.parametrize("mode", ["tcp", "tcpin"])
def test_monitor_tcp_stream_ends_when_the_sender_closes(intent, mode):
    """Over TCP the monitor ends by itself when the sender closes (no --idle-exit: neither a
    reconnecting nor a spinning receiver would end), and its standard output holds only the
    JSON lines (pymavlink's own TCP connections print "EOF on TCP socket" there)."""
    payload = _packets(20)
    if mode == "tcp":  # the monitor connects to this listening sender
        server = socket.create_server(("127.0.0.1", 0))
        port = server.getsockname()[1]
        rx = subprocess.Popen(
            [*uasnav_command(), "monitor", f"tcp:127.0.0.1:{port}", "--intent", str(intent),
             "--json-lines"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        server.settimeout(60)
        with server, server.accept()[0] as conn:
            conn.sendall(payload)
    else:  # the monitor listens; this sender connects
        port = free_port(socket.SOCK_STREAM)
        rx = subprocess.Popen(
            [*uasnav_command(), "monitor", f"tcpin:127.0.0.1:{port}", "--intent", str(intent),
             "--json-lines"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        deadline = time.monotonic() + 60.0
        while not listening(port, "tcp"):
            assert rx.poll() is None and time.monotonic() < deadline
            time.sleep(0.05)
        with socket.create_connection(("127.0.0.1", port), timeout=60) as conn:
            conn.sendall(payload)
    try:
        out, err = rx.communicate(timeout=60)
    finally:
        if rx.poll() is None:
            rx.kill()
            rx.wait()
    assert rx.returncode == 0, err
    events = [json.loads(line) for line in out.splitlines()]  # every line is JSON
    assert states(events) == ["Accepted"], events
    summary = err.strip().splitlines()[-1]
    assert count(r"(\d+) messages received", summary) == 40, summary
    assert summary.endswith("; the sender closed the connection"), summary
    assert "EOF" not in out + err


def test_tcp_stream_errors_are_one_line(intent, monkeypatch):
    import uasnav.live.stream as st

    monkeypatch.setattr(st, "CONNECT_WAIT_S", 0.3)
    port = free_port(socket.SOCK_STREAM)  # closed again: nobody listens
    r = CliRunner().invoke(main, ["monitor", f"tcp:127.0.0.1:{port}", "--intent", str(intent)])
    assert r.exit_code == 1 and r.output.count("\n") == 1, r.output
    assert r.output.startswith(f"error: connection 'tcp:127.0.0.1:{port}': cannot connect"), r.output
    with pytest.raises(Exception, match="expected tcpin:HOST:PORT"):
        st.open_connection("tcpin:127.0.0.1:http")
    with socket.create_server(("127.0.0.1", 0)) as busy:  # the port is taken
        with pytest.raises(Exception, match="cannot listen"):
            st.open_connection(f"tcpin:127.0.0.1:{busy.getsockname()[1]}")


def test_nav_live_equals_causal_bit_for_bit(shared_data, tmp_path):
    log = str(shared_data / LOG171)
    port = free_port()
    live = tmp_path / "live.csv"
    pair = start_pair(
        ["nav", "--live", f"udpin:127.0.0.1:{port}", "--out", str(live), "--idle-exit", "2"],
        ["replay", log, "--to", f"udp:127.0.0.1:{port}", "--speed", "10", "--stop-after", "60"],
        port,
    )
    # the offline run meanwhile (the live one must keep up all the same)
    causal = tmp_path / "causal.csv"
    r = CliRunner().invoke(main, ["nav", "--causal", log, "--out", str(causal)])
    assert r.exit_code == 0, r.output
    _, err, _ = pair.finish()
    a = np.loadtxt(live, delimiter=",", skiprows=1)
    b = np.loadtxt(causal, delimiter=",", skiprows=1)
    assert a.shape[0] > 1000 and "0 refused" in err
    # the live run saw the first 60 s: every row it has equals the causal run's row exactly
    assert np.array_equal(a, b[: a.shape[0]])
    assert live.read_text().splitlines()[:50] == causal.read_text().splitlines()[:50]


def test_replay_converts_dataflash_to_ground_station_messages(shared_data):
    from uasnav.live.source import log_packets, mavlink_dialect

    pk = list(log_packets(shared_data / LOG171))
    types = {p.msg.get_type() for p in pk[:4000]}
    assert {"RAW_IMU", "HEARTBEAT", "SYSTEM_TIME", "GPS_RAW_INT", "GLOBAL_POSITION_INT"} <= types
    imu_t = np.array([p.t_s for p in pk[:4000] if p.msg.get_type() == "RAW_IMU"])
    assert np.median(np.diff(imu_t)) == pytest.approx(0.02, abs=0.002)  # the logged 50 Hz
    assert all(np.diff([p.t_s for p in pk]) >= 0)
    # every message encodes (MAVLink 2) and decodes back to itself (floats as float32)
    mav = mavlink_dialect().MAVLink(None, srcSystem=1, srcComponent=1)
    for p in pk[:300]:
        back = mav.decode(bytearray(p.msg.pack(mav))).to_dict()
        for k, v in p.msg.to_dict().items():
            assert back[k] == (pytest.approx(v, rel=1e-6, abs=1e-30) if isinstance(v, float) else v)
    # the whole log encodes: RAW_IMU's int16 fields saturate (log171 logs a 35 rad/s gyro reading)
    for p in pk:
        p.msg.pack(mav)
    gyro = np.array([[p.msg.xgyro, p.msg.ygyro, p.msg.zgyro] for p in pk if p.msg.get_type() == "RAW_IMU"])
    assert gyro.max() == 32767


def test_bad_input_is_one_error_line(tmp_path):
    r = CliRunner().invoke(main, ["replay", str(tmp_path / "x.csv"), "--to", "udp:127.0.0.1:9"])
    assert r.exit_code == 1 and "cannot replay .csv" in r.output
    r = CliRunner().invoke(main, ["replay", str(tmp_path / "x.tlog"), "--to", "tcp:x"])
    assert r.exit_code == 1 and "--to: expected udp:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT" in r.output
    r = CliRunner().invoke(main, ["replay", str(tmp_path / "x.tlog"), "--to", "serial:127.0.0.1:5760"])
    assert r.exit_code == 1 and "/dev/ttyX,BAUD, got 'serial:" in r.output
    r = CliRunner().invoke(main, ["monitor", "bogus", "--intent", str(tmp_path / "none.json")])
    assert r.exit_code == 1 and "error:" in r.output
    r = CliRunner().invoke(main, ["nav", "--causal"])
    assert r.exit_code == 2 and "--causal needs LOG" in r.output
    r = CliRunner().invoke(main, ["serve", "--live-intent", str(tmp_path / "a.json")])
    assert r.exit_code == 2 and "--live-intent needs --live CONNECTION" in r.output
    r = CliRunner().invoke(main, ["serve", "--live", "udpin:127.0.0.1:9"])
    assert r.exit_code == 2 and "--live needs at least one --live-intent" in r.output


def test_replay_tcp_to_nobody_is_one_error_line(shared_data, monkeypatch):
    import uasnav.live.replay as rp

    monkeypatch.setattr(rp, "CONNECT_WAIT_S", 0.3)
    port = free_port(socket.SOCK_STREAM)  # closed again: nobody listens
    r = CliRunner().invoke(main, ["replay", str(shared_data / TLOG), "--to", f"tcp:127.0.0.1:{port}"])
    assert r.exit_code == 1 and r.output.startswith(f"error: --to tcp:127.0.0.1:{port}: cannot connect"), (
        r.output
    )


def test_kernel_drops_counts_a_full_receive_buffer():
    import types

    from uasnav.live.stream import kernel_drops

    with (
        socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as rx,
        socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx,
    ):
        rx.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        rx.bind(("127.0.0.1", 0))
        conn = types.SimpleNamespace(port=rx)
        assert kernel_drops(conn) == 0
        for _ in range(500):  # never read: the buffer fills
            tx.sendto(b"x" * 100, rx.getsockname())
        assert kernel_drops(conn) > 0
    assert kernel_drops(types.SimpleNamespace(port=None)) is None


def test_live_page_shows_the_state_change_in_chromium(shared_data, intent):
    import shutil

    from playwright.sync_api import expect, sync_playwright

    from uasnav.web.process import running_server

    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    assert chromium, "chromium is not installed: run `make setup`"
    port = free_port()
    with (
        running_server("--live", f"udpin:127.0.0.1:{port}", "--live-intent", str(intent)) as server,
        sync_playwright() as p,
    ):
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
            assert listening(port, "udp")  # serve --live receives from its start
            tx = subprocess.Popen(
                [*uasnav_command(), "replay", str(shared_data / TLOG), "--to", f"udp:127.0.0.1:{port}",
                 "--speed", "20", "--from", str(RUN[0]), "--stop-after", str(RUN[1])],
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


def test_both_filter_entry_points_check_their_arrays_alike():
    """``ins_run`` and ``InsStream.step`` view and check the IMU and GNSS arrays through one
    extractor: the same mismatch gives the same message from either."""
    from uasnav import _core
    from uasnav.errors import InputError
    from uasnav.ins.core import InsConfig

    cfg = InsConfig.for_logged_imu().filter_config(0.0)
    t = np.arange(200) * 0.01
    rows = np.zeros((200, 3))
    fix_t, fix = np.array([0.5]), np.zeros((1, 3))
    stream = _core.InsStream(config=cfg)
    for short in ("gyro", "gnss_vel"):
        args = {"imu_t": t, "gyro": rows, "accel": rows, "gnss_t": fix_t, "gnss_llh": fix, "gnss_vel": fix,
                "gnss_acc": fix}  # fmt: skip
        args[short] = args[short][:-1] if short == "gyro" else np.zeros((2, 3))
        want = (
            "gyro/accel: expected 200 rows"
            if short == "gyro"
            else "gnss_llh/gnss_vel/gnss_acc: expected 1 rows"
        )
        with pytest.raises(InputError, match=want):
            _core.ins_run(*args.values(), config=cfg)
        with pytest.raises(InputError, match=want):
            stream.step(*args.values(), np.zeros(1, dtype=np.uint64))
    with pytest.raises(InputError, match="gnss_before: expected 1 rows like gnss_t"):
        stream.step(t, rows, rows, fix_t, fix, fix, fix, np.zeros(2, dtype=np.uint64))


def _read_pty(master: int, until: subprocess.Popen[str], timeout_s: float = 120.0) -> bytes:
    """Bytes from a pseudo-terminal's master side until ``until`` exits and the line is empty."""
    import os
    import select

    data = bytearray()
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        ready, _, _ = select.select([master], [], [], 0.2)
        if ready:
            data += os.read(master, 65536)
        elif until.poll() is not None:
            return bytes(data)
    pytest.fail("the replay did not end")


def test_replay_to_a_serial_port_and_monitor_from_one(shared_data, intent):
    """``replay --to /dev/ttyX,BAUD`` writes the packets whole to a serial line, and ``monitor
    /dev/ttyX,BAUD`` reads one (a pseudo-terminal pair stands for the radio link)."""
    import os
    import tty

    from uasnav.live.source import mavlink_dialect

    master, slave = os.openpty()
    tty.setraw(master)
    try:
        tx = subprocess.Popen(
            [*uasnav_command(), "replay", str(shared_data / TLOG), "--to", f"{os.ttyname(slave)},57600",
             "--speed", "100", "--from", str(RUN[0]), "--stop-after", str(RUN[0] + 10)],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        data = _read_pty(master, tx)
        _, err = tx.communicate(timeout=60)
        assert tx.returncode == 0, err
        mav = mavlink_dialect().MAVLink(None)
        mav.robust_parsing = True
        msgs = [m for m in mav.parse_buffer(data) or [] if m.get_type() != "BAD_DATA"]
        assert len(msgs) == count(r"sent (\d+) packets", err) > 100 and count(r"\((\d+) bytes", err) == len(
            data
        )

        rx = subprocess.Popen(
            [*uasnav_command(), "monitor", f"{os.ttyname(slave)},57600", "--intent", str(intent),
             "--json-lines", "--idle-exit", "1"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        os.write(master, _packets(20))  # the line holds them until the monitor reads
        out, err = rx.communicate(timeout=60)
        assert rx.returncode == 0, err
        assert states([json.loads(line) for line in out.splitlines()]) == ["Accepted"]
        assert count(r"(\d+) messages received", err.strip().splitlines()[-1]) == 40, err
    finally:
        os.close(master)
        os.close(slave)


def test_serial_errors_are_one_line(shared_data, intent, tmp_path):
    tlog = str(shared_data / TLOG)
    for to, want in (
        (str(tmp_path / "ttyNONE"), f"tcpin:HOST:PORT or /dev/ttyX,BAUD, got '{tmp_path / 'ttyNONE'}'"),
        ("/dev/ttyNONE,57600", "error: --to /dev/ttyNONE,57600: cannot open /dev/ttyNONE"),
        ("/dev/null,57600", "error: --to /dev/null,57600: /dev/null is not a serial port"),
        ("/dev/ttyS0,fast", "--to: expected /dev/ttyX,BAUD (the baud rate a number), got '/dev/ttyS0,fast'"),
        ("/dev/ttyS0,12345", "--to /dev/ttyS0,12345: baud rate 12345 is not one this system's serial ports"),
    ):
        r = CliRunner().invoke(main, ["replay", tlog, "--to", to])
        assert r.exit_code == 1 and want in r.output and r.output.count("\n") == 1, (to, r.output)
    r = CliRunner().invoke(main, ["monitor", "/dev/null,57600", "--intent", str(intent)])
    assert r.exit_code == 1 and r.output.count("\n") == 1, r.output
    assert r.output.startswith("error: connection '/dev/null,57600': /dev/null is not a serial"), r.output
