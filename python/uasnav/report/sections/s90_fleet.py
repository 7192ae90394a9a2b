"""Report section: a simulated fleet processed on a local Dask cluster, the outliers found.

Renders :func:`uasnav.experiments.fleet.run`.
"""

from __future__ import annotations

import numpy as np

from uasnav.experiments.verdicts import majority
from uasnav.report import Section, SectionWriter


def build(w: SectionWriter) -> None:
    from uasnav.experiments import fleet
    from uasnav.plotting import new_figure

    res = fleet.run(seed=w.seed, quick=w.quick, progress=w.progress)
    where = "in this process (--quick)" if res.workers == 0 else f"on a LocalCluster of {res.workers} workers"
    w.p(
        f"A synthetic fleet of {res.n_logs} files (CSV v1 IMU logs from the simulator: each vehicle one "
        "LSM6DSM or AX1 part of its own quality, a static warm-up on the ground, then manoeuvres and "
        "vibration; a few IMUs with 8× white noise; corrupt files) went through `uasnav fleet "
        f"imu-health` {where}: {res.n_ok} logs processed, {res.n_errors} unreadable, in "
        f"{res.wall_s:.1f} s ({res.cpu_s:.1f} CPU-s over the logs, {res.bytes_read / 1e6:.1f} MB read). "
        "Each log's noise terms come from uasnav.allan/noise on its longest static interval "
        "(uasnav.stationary); the anomaly score is the largest robust z-score within the IMU model."
    )
    sentence = w.verdict("faulty_found", majority(len(res.found), len(res.found) + len(res.missed)))
    w.p(
        f"Faulty IMUs flagged as outliers: {sentence}; missed: "
        f"{', '.join(i.file for i in res.missed) or 'none'}; healthy IMUs flagged: "
        f"{', '.join(i.file for i in res.false_alarms) or 'none'}."
    )
    w.table(
        ["file", "vehicle", "model", "gyro white (rad/√s)", "accel white (m/s/√s)", "score", "driver",
         "outlier", "faulty (truth)"],
        [
            [i.file, i.vehicle, i.imu_model, i.gyro_white, i.accel_white,
             None if np.isnan(i.score) else i.score, i.driver, "yes" if i.outlier else "",
             "yes" if i.faulty else ""]
            for i in res.imus
        ],
        caption="Per IMU: white noise of the static interval, anomaly score (— : fewer than 5 IMUs "
        "of that model to compare with), outlier flag and the generator's truth.",
        fmt="{:.3g}",
    )  # fmt: skip
    w.table(["file", "error"], [list(e) for e in res.errors], caption="The errors table: unreadable logs.")
    fig, ax = new_figure()
    for model, marker in (("lsm6dsm", "o"), ("ax1", "s")):
        sel = [i for i in res.imus if i.imu_model == model]
        if not sel:
            continue
        x = [i.gyro_white for i in sel]
        y = [i.accel_white for i in sel]
        c = ["tab:red" if i.outlier else "tab:blue" for i in sel]
        ax.scatter(x, y, c=c, marker=marker, label=model)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("gyro white noise (rad/√s)")
    ax.set_ylabel("accelerometer white noise (m/s/√s)")
    ax.legend()
    ax.set_title("Fleet IMU noise (red: outliers)")
    w.figure(fig, "noise", "Static white noise of every IMU of the fleet; outliers in red.")
    w.data["fleet"] = {
        "n_logs": res.n_logs,
        "n_ok": res.n_ok,
        "n_errors": res.n_errors,
        "workers": res.workers,
        "wall_s": res.wall_s,
        "found": [i.file for i in res.found],
        "missed": [i.file for i in res.missed],
        "false_alarms": [i.file for i in res.false_alarms],
    }


SECTION = Section("fleet", "Fleet scale: IMU health of a simulated fleet on Dask", 90, build)
