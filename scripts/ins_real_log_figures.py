"""The issue-15 real-log figures of BENCHMARKS.md in one run.

::

    python scripts/ins_real_log_figures.py [--declination DEG] [--outages] [--shared ../shared]

log171 (airborne 84–238 s, the crash left out) for each IMU and the aligned three-IMU fusion
against the autopilot's EKF1 (RMS and p95 of horizontal, vertical, velocity, roll/pitch, yaw), the
ALFA Carbon-Z flight and the PX4 ULog excerpt against their autopilots; with ``--outages`` the
GNSS-outage experiments (log171 IMU and fused: 10/30/60 s × 4 starts over 84–238 s; ALFA:
10/30 s × 4). ``--declination`` overrides the magnetic declination (default: the log's, else
the World Magnetic Model). Prints JSON.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any


def _row(c: Any, r: Any) -> dict[str, Any]:
    d = {k: (round(v, 3) if isinstance(v, float) else v) for k, v in c.as_dict().items() if k != "t_span"}
    d["declination_deg"] = round(r.summary["declination_deg"], 3)
    d["declination_source"] = r.summary["declination_source"]
    d["fixes_excluded"] = r.summary["fixes_excluded"]
    return d


def main() -> None:
    from uasnav import ins, redundancy
    from uasnav.ins import evaluate as ev
    from uasnav.io import read_nav

    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--declination", type=float, default=None, help="degrees, east positive")
    ap.add_argument("--outages", action="store_true", help="also the GNSS-outage experiments")
    ap.add_argument("--shared", default=str(Path(__file__).resolve().parents[1] / ".." / "shared"))
    a = ap.parse_args()
    data = Path(a.shared) / "data"
    cfg = ins.InsConfig.for_logged_imu(declination_deg=a.declination)
    out: dict[str, Any] = {}
    f = read_nav(data / "logs" / "ardupilot_log171.bin").between(0.0, 238.0)
    logs = [f.imus[n] for n in f.imus]
    fused = redundancy.fuse(logs, redundancy.array_for_logs("aligned", logs)).to_log()
    for name, imu in [*f.imus.items(), ("fused", fused)]:
        fl = f.with_imu(imu, name)
        r = ins.run(fl, cfg)
        assert f.reference is not None
        out[f"log171 {name}"] = _row(ev.compare(r, f.reference, t_range=(84.0, 238.0)), r)
        if a.outages and name in ("IMU", "fused"):
            t = ev.outage_experiment(
                fl, (10.0, 30.0, 60.0), config=cfg, per_duration=4, interval=(84.0, 238.0), imu_name=name
            )
            out[f"log171 {name} outages"] = {
                "summary": t.summary(),
                "each": [
                    [o.start, o.duration, round(o.horizontal_error_m, 1), round(o.vertical_error_m, 2)]
                    for o in t.outages
                ],
            }
    alfa = read_nav(data / "flights" / "alfa_carbonz_engine_failure")
    r = ins.run(alfa, cfg)
    assert alfa.reference is not None
    out["alfa"] = _row(ev.compare(r, alfa.reference), r)
    if a.outages:
        out["alfa outages"] = ev.outage_experiment(alfa, (10.0, 30.0), config=cfg, per_duration=4).summary()
    px4 = read_nav(data / "logs" / "px4_sample_log_small.ulg")
    r = ins.run(px4, cfg)
    assert px4.reference is not None
    out["px4 excerpt"] = _row(ev.compare(r, px4.reference), r)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
