"""Bounded load test of ``uasnav serve`` on loopback.

Starts the real command (``uasnav serve --port <free port>``), runs CLIENTS concurrent clients
for DURATION seconds, each posting the thesis' precision-agriculture scenario to
``/api/select`` over its own keep-alive connection as fast as the answers come back, then stops
the server. Prints the throughput, the latency percentiles and the failures; exits 1 if any
request failed or answered anything but 200 with the expected ranking.

Run: ``.venv/bin/python benches/web_load.py [--clients 20] [--duration 10] [--json]``.
The machine is shared: quote the median of several runs.
"""

from __future__ import annotations

import argparse
import http.client
import json
import sys
import threading
import time

import numpy as np

from uasnav.web.process import running_server

THESIS = {
    "mission": "precision-agriculture",
    "range": 1500,
    "resolution": 0.05,
    "image_size": "70x70",
    "altitude": 50,
    "imagery": "multispectral",
    "wind": 5,
    "order_by": "cost",
}


def client(port: int, stop_at: float, expected_first: str, out: list[float], failures: list[str]) -> None:
    body = json.dumps(THESIS).encode()
    headers = {"content-type": "application/json", "host": f"127.0.0.1:{port}"}
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    while time.perf_counter() < stop_at:
        t0 = time.perf_counter()
        try:
            conn.request("POST", "/api/select", body=body, headers=headers)
            r = conn.getresponse()
            data = r.read()
            dt = time.perf_counter() - t0
            if r.status != 200 or json.loads(data)["ranking"][0]["uas"] != expected_first:
                failures.append(f"status {r.status}")
            else:
                out.append(dt)
        except Exception as e:  # a failed request is counted, never hidden
            failures.append(f"{type(e).__name__}: {e}")
            conn.close()
            conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    conn.close()


def run(clients: int, duration_s: float) -> dict[str, float]:
    with running_server() as s:
        c = http.client.HTTPConnection("127.0.0.1", s.port, timeout=30)
        c.request(
            "POST", "/api/select", body=json.dumps(THESIS), headers={"content-type": "application/json"}
        )
        first = json.loads(c.getresponse().read())["ranking"][0]["uas"]
        c.close()
        lat: list[list[float]] = [[] for _ in range(clients)]
        failures: list[str] = []
        t0 = time.perf_counter()
        stop_at = t0 + duration_s
        threads = [
            threading.Thread(target=client, args=(s.port, stop_at, first, lat[i], failures))
            for i in range(clients)
        ]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        elapsed = time.perf_counter() - t0
    all_lat = np.concatenate([np.asarray(x) for x in lat]) if any(lat) else np.zeros(0)
    return {
        "clients": clients,
        "duration_s": round(elapsed, 2),
        "requests": int(all_lat.size),
        "failed": len(failures),
        "throughput_rps": round(all_lat.size / elapsed, 1),
        "p50_ms": round(float(np.percentile(all_lat, 50)) * 1e3, 1) if all_lat.size else float("nan"),
        "p90_ms": round(float(np.percentile(all_lat, 90)) * 1e3, 1) if all_lat.size else float("nan"),
        "p99_ms": round(float(np.percentile(all_lat, 99)) * 1e3, 1) if all_lat.size else float("nan"),
        "max_ms": round(float(all_lat.max()) * 1e3, 1) if all_lat.size else float("nan"),
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clients", type=int, default=20)
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    r = run(a.clients, a.duration)
    if a.json:
        print(json.dumps(r))
    else:
        print(
            f"uasnav serve /api/select, {r['clients']} clients x {r['duration_s']} s: "
            f"{r['requests']} requests, "
            f"{r['failed']} failed, {r['throughput_rps']} req/s, p50 {r['p50_ms']} ms, p90 {r['p90_ms']} ms, "
            f"p99 {r['p99_ms']} ms, max {r['max_ms']} ms"
        )
    return 1 if r["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
