# ruff: noqa: E501  (the probe table reads best one probe per line)
"""Re-run the hostile-input probe classes against the real ``uasnav`` command, one subprocess per
probe, and report the share that give one clear line.

A probe passes when the command either succeeds without a traceback, or fails with exit code 1
or 2 and its stderr holds exactly one ``error:`` line (click's usage errors: one ``Error:``
line), with no "internal error" and no traceback; its input files are unchanged; and it ends
within its deadline (``--deadline``, default 60 s: a hang detector on a shared machine, not a
benchmark). Everything it builds lives in a temporary directory; its servers listen on
127.0.0.1 only and stop with the script.

    python scripts/hostile_probes.py [--only CLASS] [--json]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import random
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
TLOG = DATA / "flights" / "phoenix_mission1_arducopter.tlog"
PLAN = DATA / "missions" / "mavsdk_qgroundcontrol_sample.plan"
ZONES = DATA / "utm" / "interuss_ed269_geozone_sample.json"
ENTRY = "import sys; from uasnav.cli import main; sys.exit(main())"
GNSS_HEADER = "t,lat,lon,alt,vn,ve,vd,h_acc,v_acc,s_acc\n"


@dataclass
class Probe:
    klass: int
    name: str
    argv: list[str]
    env: dict[str, str] = field(default_factory=dict)


@dataclass
class Outcome:
    probe: Probe
    ok: bool
    code: int | None
    seconds: float
    why: str
    line: str


class Loopback:
    """127.0.0.1 TCP server: ``silent`` accepts and never speaks; ``drip`` answers HTTP one byte
    per second. Stops by itself after ``lifetime_s``."""

    def __init__(self, mode: str, lifetime_s: float = 600.0) -> None:
        self.mode, self.end = mode, time.monotonic() + lifetime_s
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.conns: list[socket.socket] = []
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while time.monotonic() < self.end:
            try:
                c, _ = self.sock.accept()
            except OSError:
                continue
            self.conns.append(c)
            if self.mode == "drip":
                threading.Thread(target=self._drip, args=(c,), daemon=True).start()
        self.close()

    def _drip(self, c: socket.socket) -> None:
        try:
            c.recv(65536)
            c.sendall(b"HTTP/1.1 200 OK\r\nContent-Length: 1000000\r\n\r\n")
            while time.monotonic() < self.end:
                c.sendall(b"x")
                time.sleep(1.0)
        except OSError:
            pass

    def close(self) -> None:
        self.end = 0.0
        for c in [self.sock, *self.conns]:
            try:
                c.close()
            except OSError:
                pass


def _flipped(src: Path, dst: Path, n: int, seed: int = 1) -> Path:
    data = bytearray(src.read_bytes())
    rng = random.Random(seed)
    for _ in range(n):
        i = rng.randrange(len(data))
        data[i] ^= 1 << rng.randrange(8)
    dst.write_bytes(bytes(data))
    return dst


def build(d: Path) -> tuple[list[Probe], list[Loopback]]:
    """The probes, with their inputs written under ``d``."""
    w: Callable[[str, str | bytes], str] = lambda name, text: _write(d / name, text)  # noqa: E731
    imu_rows = "".join(f"{i / 100:.2f},0,0,0,0,0,9.81\n" for i in range(3000))
    imu = w("imu.csv", "t,gx,gy,gz,ax,ay,az\n" + imu_rows)
    big = w("big.csv", "t,gx,gy,gz,ax,ay,az\n" + imu_rows.replace("1.00,0,", "1.00,1.79e308,", 1))
    cold = w("cold.csv", "t,gx,gy,gz,ax,ay,az,temp\n" + imu_rows.replace(",9.81\n", ",9.81,25\n").replace(
        "0.50,0,0,0,0,0,9.81,25", "0.50,0,0,0,0,0,9.81,-300", 1))  # fmt: skip
    fix = "".join(f"{i / 5:.1f},47.0,{{lon}},{{alt}},0,0,0,1,1,0.1\n" for i in range(100))
    g_hdr = w("gnss_header.csv", GNSS_HEADER)
    g_lon = w("gnss_lon.csv", GNSS_HEADER + fix.format(lon=1000, alt=400))
    g_alt = w("gnss_alt.csv", GNSS_HEADER + fix.format(lon=8, alt="1e308"))
    mount = w("mount_bad.csv", "# mounting: [[1,0\n" + "t,gx,gy,gz,ax,ay,az\n" + imu_rows)
    mount_ok = w(
        "mount_ok.csv", "# mounting: [[1,0,0],[0,1,0],[0,0,1]]\n" + "t,gx,gy,gz,ax,ay,az\n" + imu_rows
    )
    p_empty, p_list = w("empty.json", ""), w("list.json", "[1, 2]")
    p_deep = w("deep.json", '{"a":' * 3000 + "1" + "}" * 3000)
    area2 = w("area2.geojson", json.dumps({"type": "Polygon", "coordinates": [[[8, 47], [8.01, 47]]]}))
    laughs = "\n".join(
        ["a0: &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
        + [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]" for i in range(1, 9)]
        + ["intents: *a8"]
    )
    bomb = w("bomb.yaml", laughs)
    deep_yaml = w("deep.yaml", "intents: " + "[" * 5000 + "]" * 5000 + "\n")
    bad_tlog = str(_flipped(TLOG, d / "bad.tlog", 10_000))
    sched = w("sched.json", "garbage\n")
    fifo = d / "in.csv"
    os.mkfifo(fifo)
    logs = d / "logs"
    logs.mkdir()
    _write(logs / "a.csv", "t,gx,gy,gz,ax,ay,az\n" + imu_rows[:3000])
    big_plan = w(
        "big_plan.csv", "north,east\n" + "".join(f"{(i % 2) * 50.0},{i * 10.0}\n" for i in range(100_000))
    )
    model = _model(d)
    hold = w(
        "hold.waypoints",
        "QGC WPL 110\n"
        + "".join(
            "\t".join(map(str, r)) + "\n"
            for r in [
                (0, 1, 0, 16, 0, 0, 0, 0, 47.0, 8.0, 400, 1),
                (1, 0, 3, 22, 0, 0, 0, 0, 47.0, 8.0, 30, 1),
                (2, 0, 3, 16, "1e12", 0, 0, 0, 47.001, 8.0, 30, 1),
                (3, 0, 3, 16, 0, 0, 0, 0, 47.002, 8.0, 30, 1),
            ]
        ),
    )
    thermal = _thermal_model_with_weight(d, 1e308)
    long_logs = d / "long_logs"
    long_logs.mkdir()
    _npz(long_logs / "long.npz", 1_000_000)
    _npz(long_logs / "short.npz", 20_000)
    million = _npz(d / "million.npz", 1_000_000)
    flight = d / "flight.csv"
    sim = subprocess.run(
        [
            sys.executable,
            "-c",
            ENTRY,
            "simulate",
            "--profile",
            "flight",
            "--duration",
            "60",
            "--out",
            str(flight),
        ],
        capture_output=True,
        text=True,
    )
    if sim.returncode != 0:
        raise SystemExit(f"cannot build the simulated flight: {sim.stderr}")
    sweep = ",".join(f"{1 + 0.05 * i:g}" for i in range(3000))
    intents = str(DATA / "utm" / "interuss_flight_intents_conflicting.yaml")
    intent = ["trajectory", "intent", "--model", model, "--plan", str(PLAN), "--wind", "0@0"]
    start = ["--start", "2026-01-01T00:00:00Z"]
    silent, drip = Loopback("silent"), Loopback("drip")
    urls = w("slow.urls", f"http://127.0.0.1:{drip.port}/a.ulg\n")
    out = str(d / "out")
    P = Probe
    probes = [
        P(1, "allan on a tlog with 10 000 flipped bits", ["allan", bad_tlog, "--json"]),
        P(1, "fleet: a long log stopped at --log-timeout 1", ["fleet", "imu-health", str(long_logs), "--out",
                                                              out + "_health.parquet", "--workers", "0", "--log-timeout", "1"]),
        P(2, "billion laughs intent YAML", ["utm", "deconflict", bomb]),
        P(2, "deeply nested intent YAML", ["utm", "deconflict", deep_yaml]),
        P(3, "calibrate --runs 100000", ["trajectory", "calibrate", "--model", p_list, "--runs", "100000",
                                         "--out", out + ".json"]),
        P(3, "UASNAV_MAX_WORK=abc", ["simulate", "--duration", "1", "--out", out + ".csv"], {"UASNAV_MAX_WORK": "abc"}),
        P(3, "UASNAV_MAX_MEMORY=-1", ["simulate", "--duration", "1", "--out", out + ".csv"], {"UASNAV_MAX_MEMORY": "-1"}),
        P(3, "allan --taus all under a small work limit", ["allan", imu, "--taus", "all"], {"UASNAV_MAX_WORK": "1000"}),
        P(3, "UASNAV_MAX_WORK=nan", ["allan", imu], {"UASNAV_MAX_WORK": "nan"}),
        P(3, "UASNAV_MAX_MEMORY= (empty)", ["allan", imu], {"UASNAV_MAX_MEMORY": ""}),
        P(3, "allan --taus all on 10⁶ samples", ["allan", million, "--taus", "all"]),
        P(3, "fleet simulate --nav-flights 100 × 100 vehicles", ["fleet", "simulate", "--vehicles", "100", "--flights", "1",
                                                                 "--nav-flights", "100", "--out", out + "_fleet"]),
        P(3, "nav --outage-sweep of 3000 durations", ["nav", str(flight), "--gnss", str(d / "flight_gnss.csv"),
                                                      "--outage-sweep", sweep]),
        P(4, "CSV cell 1.79e308 (allan)", ["allan", big]),
        P(4, "intent --start 9999-12-31T23:59:59Z", [*intent, "--start", "9999-12-31T23:59:59Z", "--out", out + ".json"]),
        P(4, "a plan hold of 10¹² s (intent)", [*intent[:5], hold, *intent[6:], *start, "--out", out + ".json"]),
        P(4, "utm deconflict --now 0001-01-01T00:00:00Z", ["utm", "deconflict", intents, "--now", "0001-01-01T00:00:00Z"]),
        P(4, "intent --lateral-buffer 1e308", [*intent, *start, "--lateral-buffer", "1e308", "--out", out + ".json"]),
        P(4, "utm deconflict --horizontal-buffer 1e308", ["utm", "deconflict", intents, "--horizontal-buffer", "1e308"]),
        P(4, "simulate --duration 1e308", ["simulate", "--profile", "flight", "--duration", "1e308", "--out", out + ".csv"]),
        P(4, "zupt --levelling-s 1e308", ["zupt", imu, "--levelling-s", "1e308"]),
        P(4, "GNSS CSV with only a header", ["nav", imu, "--gnss", g_hdr]),
        P(4, "Parquet of the wrong schema", ["trajectory", "train", _parquet(d), "--out", out + ".json"]),
        P(4, "malformed # mounting:", ["redundancy", "fuse", "--shape", "meta", mount, mount_ok, mount_ok,
                                       "--out", out + ".csv"]),
        P(4, "preset JSON empty", ["simulate", "--preset", p_empty, "--duration", "1", "--out", out + ".csv"]),
        P(4, "preset JSON a list", ["simulate", "--preset", p_list, "--duration", "1", "--out", out + ".csv"]),
        P(4, "preset JSON deeply nested", ["simulate", "--preset", p_deep, "--duration", "1", "--out", out + ".csv"]),
        P(4, "two-point --area with --zones", ["select", "--area", area2, "--zones", str(ZONES)]),
        P(4, "db validate 'http://[::1'", ["db", "validate", "http://[::1"]),
        P(4, "fleet --scheduler-file garbage", ["fleet", "scan", str(logs), "--out", out + ".parquet",
                                                "--scheduler-file", sched]),
        P(4, "fleet --scheduler xyz://", ["fleet", "scan", str(logs), "--out", out + ".parquet", "--scheduler", "xyz://"]),
        P(5, "a FIFO as allan's input", ["allan", str(fifo)]),
        P(5, "a FIFO as zupt's input", ["zupt", str(fifo)]),
        P(5, "fleet --scheduler on a port that never speaks Dask",
          ["fleet", "scan", str(logs), "--out", out + ".parquet", "--scheduler", f"tcp://127.0.0.1:{silent.port}"]),
        P(5, "fleet URL list with a slow-drip server", ["fleet", "scan", urls, "--out", out + "2.parquet",
                                                        "--workers", "0", "--log-timeout", "5"]),
        P(6, "predict a 10⁵-point plan", ["trajectory", "predict", "--model", model, "--plan", big_plan,
                                          "--wind", "0@0", "--json"]),
        P(8, "select --max-distance 1e308", ["select", "--max-distance", "1e308"]),
        P(8, "select --range 1e-320", ["select", "--range", "1e-320"]),
        P(8, "predict --speed 1e6", ["trajectory", "predict", "--model", p_list, "--plan", str(PLAN), "--wind", "0@0",
                                     "--speed", "1e6"]),
        P(8, "predict --speed 1e-300", ["trajectory", "predict", "--model", p_list, "--plan", str(PLAN),
                                        "--wind", "0@0", "--speed", "1e-300"]),
        P(8, "GNSS longitude 1000°", ["nav", imu, "--gnss", g_lon]),
        P(8, "GNSS altitude 1e308", ["nav", imu, "--gnss", g_alt]),
        P(8, "die temperature below absolute zero", ["allan", cold]),
        P(8, "thermal network weight 1e308", ["zupt", imu, "--model", thermal]),
        P(8, "intent --climb-rate 1e-300", [*intent, *start, "--climb-rate", "1e-300", "--out", out + ".json"]),
        P(8, "--out m.json/", ["simulate", "--duration", "1", "--out", out + "/m.json/"]),
    ]  # fmt: skip
    return probes, [silent, drip]


def _write(p: Path, text: str | bytes) -> str:
    if isinstance(text, bytes):
        p.write_bytes(text)
    else:
        p.write_text(text)
    return str(p)


def _parquet(d: Path) -> str:
    import pyarrow as pa
    import pyarrow.parquet as pq

    p = d / "wrong.parquet"
    pq.write_table(pa.table({"a": [1, 2], "b": ["x", "y"]}), p)
    return str(p)


def _model(d: Path) -> str:
    """A kinematic trajectory model trained on the Phoenix log."""
    p = d / "model.json"
    res = subprocess.run([sys.executable, "-c", ENTRY, "trajectory", "train", str(TLOG), "--method", "kinematic",
                          "--out", str(p)], capture_output=True, text=True)  # fmt: skip
    if res.returncode != 0:
        raise SystemExit(f"cannot train the probes' model: {res.stderr}")
    return str(p)


def _npz(p: Path, n: int) -> str:
    """A static IMU log of ``n`` samples at 100 Hz (compressed: a few MB even for 10⁶ samples)."""
    import numpy as np

    accel = np.zeros((n, 3))
    accel[:, 2] = -9.80665
    np.savez_compressed(p, t=np.arange(n) / 100.0, gyro=np.zeros((n, 3)), accel=accel,
                        meta_json=np.array("{}"), format=np.array("uasnav-npz/1"))  # fmt: skip
    return str(p)


def _thermal_model_with_weight(d: Path, weight: float) -> str:
    """A neural thermal model file (re-signed) whose first hidden weight is ``weight``."""
    import numpy as np

    from uasnav.thermal import NeuralBiasModel, dumps_model
    from uasnav.thermal.modelfile import ZEROS, file_checksum

    t = np.linspace(-10.0, 40.0, 200)
    b = np.stack([1e-3 * np.tanh((t - 15) / 10), 2e-4 * np.sin(t / 9), 3e-6 * (t - 5) ** 2], 1)
    doc = json.loads(dumps_model(NeuralBiasModel(2, restarts=1, max_epochs=20).fit(t, b)))
    doc["models"][0]["layers"][0]["weights"][0][0] = weight
    doc["checksum"] = {"algorithm": "sha256", "value": ZEROS}
    text = json.dumps(doc)
    p = d / "thermal.json"
    p.write_text(text.replace(ZEROS, file_checksum(text, ZEROS), 1))
    return str(p)


def _digest(d: Path) -> dict[str, str]:
    out = {}
    for p in sorted(d.rglob("*")):
        if p.is_file() and not p.is_fifo():
            out[str(p)] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def run_probe(probe: Probe, d: Path, deadline_s: float) -> Outcome:
    before = _digest(d)
    t0 = time.monotonic()
    try:
        res = subprocess.run(
            [sys.executable, "-c", ENTRY, *probe.argv],
            capture_output=True,
            text=True,
            timeout=deadline_s,
            env={**os.environ, **probe.env},
            stdin=subprocess.DEVNULL,
        )
    except subprocess.TimeoutExpired:
        return Outcome(probe, False, None, time.monotonic() - t0, f"no answer within {deadline_s:g} s", "")
    took = time.monotonic() - t0
    err = [ln for ln in res.stderr.splitlines() if ln.strip()]
    errors = [ln for ln in err if ln.startswith(("error:", "Error:"))]
    line = errors[0] if errors else (err[-1] if err else "")
    changed = [p for p, h in before.items() if _digest(d).get(p) != h]
    if "Traceback" in res.stderr or "internal error" in res.stderr:
        why = "traceback or internal error"
    elif changed:
        why = f"input changed: {changed[0]}"
    elif res.returncode == 0:
        why = ""
    elif res.returncode not in (1, 2):
        why = f"exit code {res.returncode}"
    elif len(errors) != 1:
        why = f"{len(errors)} error lines"
    elif res.returncode == 1 and len(err) != 1:
        why = f"{len(err)} stderr lines"
    else:
        why = ""
    return Outcome(probe, not why, res.returncode, took, why, line)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", type=int, help="run one class only")
    ap.add_argument(
        "--deadline", type=float, default=60.0, help="seconds per probe before it counts as a hang"
    )
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="uasnav-probes-") as tmp:
        d = Path(tmp)
        probes, servers = build(d)
        try:
            outcomes = [run_probe(p, d, args.deadline) for p in probes if args.only in (None, p.klass)]
        finally:
            for s in servers:
                s.close()
    n_ok = sum(o.ok for o in outcomes)
    if args.json:
        print(json.dumps({
            "probes": len(outcomes), "clear": n_ok, "share": n_ok / max(1, len(outcomes)),
            "results": [{"class": o.probe.klass, "probe": o.probe.name, "ok": o.ok, "exit": o.code,
                         "seconds": round(o.seconds, 2), "why": o.why, "line": o.line} for o in outcomes],
        }, indent=2, ensure_ascii=False))  # fmt: skip
    else:
        for o in outcomes:
            mark = "ok  " if o.ok else "FAIL"
            print(
                f"{mark} [{o.probe.klass}] {o.probe.name} ({o.seconds:.1f} s, exit {o.code}) {o.why} {o.line[:160]}"
            )
        print(
            f"{n_ok}/{len(outcomes)} probes give one clear line ({100 * n_ok / max(1, len(outcomes)):.0f} %)"
        )
    return 0 if n_ok == len(outcomes) else 1


if __name__ == "__main__":
    sys.exit(main())
