"""Fleet speed-up, 1 vs 2 workers: three runs per worker count, interleaved (1, 2, 1, 2, 1, 2) on
clusters started and warmed up once, so both see the same machine load; medians. Then the
per-log CPU-seconds of ``uasnav fleet nav`` (GNSS/INS replay + 9 outage runs).

Run: ``.venv/bin/python benches/bench_fleet_speedup.py`` (about 3 minutes).
"""

import resource
import statistics
import tempfile
import time
from pathlib import Path

from distributed import Client

from uasnav import fleet
from uasnav.fleet.nav import NAV

N_VEHICLES, N_FLIGHTS, DURATION_S, RUNS = 5, 8, 120.0, 3


def _cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main() -> None:
    with tempfile.TemporaryDirectory(prefix="bench-fleet-") as tmp:
        src = Path(tmp) / "fleet"
        fleet.simulate_fleet(src, N_VEHICLES, N_FLIGHTS, seed=1, duration_s=DURATION_S, corrupt=False)
        mb = sum(f.stat().st_size for f in src.rglob("*.csv")) / 1e6
        n = N_VEHICLES * N_FLIGHTS
        clusters = {}
        for w in (1, 2):
            cluster = fleet.local_cluster(w)
            client = Client(cluster)
            clusters[w] = (cluster, client)
            warm = [str(p) for p in sorted(src.rglob("*.csv"))[:w]]
            for a in (fleet.IMU_HEALTH, fleet.SCAN):
                fleet.run(a, warm, Path(tmp) / f"warm-{a.name}-{w}", client=client)
        for a in (fleet.IMU_HEALTH, fleet.SCAN):
            times: dict[int, list[float]] = {1: [], 2: []}
            for k in range(RUNS):
                for w in (1, 2):
                    t0 = time.perf_counter()
                    fleet.run(a, [src], Path(tmp) / f"{a.name}-{w}-{k}.parquet", client=clusters[w][1])
                    times[w].append(time.perf_counter() - t0)
                t1, t2 = times[1][-1], times[2][-1]
                print(
                    f"{a.name} run {k + 1}: 1w {n / t1:.2f} logs/s, 2w {n / t2:.2f} logs/s, "
                    f"ratio {t1 / t2:.2f}"
                )
            m1, m2 = statistics.median(times[1]), statistics.median(times[2])
            ratios = [x / y for x, y in zip(times[1], times[2], strict=True)]
            print(
                f"{a.name} median: 1w {n / m1:.2f} logs/s {mb / m1:.1f} MB/s, 2w {n / m2:.2f} logs/s "
                f"{mb / m2:.1f} MB/s, speed-up {m1 / m2:.2f}x; "
                f"median of per-run ratios {statistics.median(ratios):.2f}"
            )
        for cluster, client in clusters.values():
            client.close()
            cluster.close()
        nav_dir = Path(tmp) / "nav"
        fleet.simulate_fleet(nav_dir, 1, 1, seed=1, duration_s=10.0, corrupt=False, nav_flights=1)
        shared = Path(__file__).resolve().parents[2] / "shared" / "data" / "logs"
        for label, p in (
            ("simulated flight, 180 s at 100 Hz", nav_dir / "V01" / "nav_001.csv"),
            ("log171.bin", shared / "ardupilot_log171.bin"),
            ("px4_sample_log_small.ulg", shared / "px4_sample_log_small.ulg"),
        ):
            if not p.exists():
                continue
            NAV.compute(str(p))  # warm-up
            cpus = []
            for _ in range(RUNS):
                c0 = _cpu_s()
                NAV.compute(str(p))
                cpus.append(_cpu_s() - c0)
            each = ", ".join(f"{c:.2f}" for c in cpus)
            print(f"nav CPU-s {label}: median {statistics.median(cpus):.2f} ({each})")


if __name__ == "__main__":  # the LocalCluster's worker processes import this file
    main()
