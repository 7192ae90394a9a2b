"""Live telemetry: what one core sustains.

- Conformance monitoring: messages per second through pymavlink's decoder and
  :class:`uasnav.live.conformance.ConformanceMonitor` for ``--vehicles`` vehicles, each sending
  the Phoenix flight's GLOBAL_POSITION_INT/HEARTBEAT/SYSTEM_TIME stream (its intent built as in
  ``tests/test_live.py`` is given with ``--intent``); the per-message time is also the
  latency from a message to its event, since events are emitted on the message.
- Navigation: IMU samples per second through :class:`uasnav.live.nav.LiveNav` (the streaming
  binding) on log171's converted stream.

Usage::

    .venv/bin/python benches/live_bench.py --intent phoenix.json \
        --tlog ../shared/data/flights/phoenix_mission1_arducopter.tlog \
        --bin ../shared/data/logs/ardupilot_log171.bin
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def monitor_rate(intent_path: str, tlog: str, vehicles: int) -> dict[str, float]:
    from uasnav.io.operational_intent import read_intents
    from uasnav.live.conformance import ConformanceMonitor
    from uasnav.live.source import log_packets, mavlink_dialect

    keep = {"GLOBAL_POSITION_INT", "HEARTBEAT", "SYSTEM_TIME", "GPS_RAW_INT"}
    msgs = [pk.msg for pk in log_packets(tlog) if pk.msg.get_type() in keep and pk.msg.get_srcSystem() == 1]
    intents = read_intents(intent_path)
    mon = ConformanceMonitor(intents, {k + 1: intents[0].name for k in range(vehicles)})
    mav = mavlink_dialect().MAVLink(None)
    wires = []
    for k in range(vehicles):
        enc = mavlink_dialect().MAVLink(None, srcSystem=k + 1, srcComponent=1)
        wires += [bytes(m.pack(enc)) for m in msgs]
    per = []
    t0 = time.perf_counter()
    for w in wires:
        a = time.perf_counter()
        m = mav.parse_char(w)
        mon.on_message(m, a)
        per.append(time.perf_counter() - a)
    total = time.perf_counter() - t0
    per_us = np.array(per) * 1e6
    return {
        "messages": len(wires),
        "msg_per_s": len(wires) / total,
        "p50_us": float(np.percentile(per_us, 50)),
        "p99_us": float(np.percentile(per_us, 99)),
        "max_us": float(per_us.max()),
    }


def nav_rate(binlog: str) -> dict[str, float]:
    from uasnav.live.nav import LiveNav
    from uasnav.live.source import log_packets

    msgs = [pk.msg for pk in log_packets(binlog)]
    nav = LiveNav()
    t0 = time.perf_counter()
    rows = 0
    for m in msgs:
        nav.on_message(m)
        if nav.pending >= 256:
            rows += len(nav.flush())
    rows += len(nav.flush())
    total = time.perf_counter() - t0
    return {"imu_samples": nav.imu_messages, "imu_per_s": nav.imu_messages / total, "solutions": rows}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--intent", required=True)
    ap.add_argument("--tlog", required=True)
    ap.add_argument("--bin", required=True)
    ap.add_argument("--vehicles", type=int, default=20)
    a = ap.parse_args()
    m = monitor_rate(a.intent, a.tlog, a.vehicles)
    print(
        f"monitor: {m['messages']} messages of {a.vehicles} vehicles, "
        f"{m['msg_per_s']:.0f} msg/s on one core; "
        f"per message p50 {m['p50_us']:.0f} µs, p99 {m['p99_us']:.0f} µs, max {m['max_us'] / 1e3:.1f} ms"
    )
    n = nav_rate(a.bin)
    print(
        f"nav: {n['imu_samples']} IMU samples at {n['imu_per_s']:.0f} samples/s (decode excluded), "
        f"{n['solutions']} solutions"
    )


if __name__ == "__main__":
    main()
