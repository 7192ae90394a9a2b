"""Fleet experiment: a simulated fleet's IMU health computed on a local Dask cluster, and the
faulty IMUs the fleet-relative anomaly score finds.

The fleet is :func:`uasnav.fleet.simulate_fleet` (5 vehicles × 4 flights of 120 s, one or two
faulty IMUs, a corrupt file; ``quick``: 3 × 2 flights of 40 s, processed in this process to stay
within seconds); :data:`uasnav.fleet.IMU_HEALTH` runs over it on a
``distributed.LocalCluster`` of two worker processes; the outliers are compared with the
generator's truth.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

Progress = Callable[[str], None]


@dataclass(frozen=True)
class FleetImu:
    """One IMU of the simulated fleet, as the health table and the truth see it."""

    file: str
    vehicle: str
    imu_model: str
    gyro_white: float  # mean over axes, rad/√s (null → NaN)
    accel_white: float  # m/s/√s
    score: float  # anomaly score (NaN if none)
    driver: str
    outlier: bool
    faulty: bool


@dataclass(frozen=True)
class FleetResult:
    """The fleet run and what it found.

    Attributes
    ----------
    n_logs, n_ok, n_errors : int
        Files found, processed, unreadable (errors table).
    errors : tuple of (file, message)
    imus : tuple of FleetImu
    workers : int
        Dask workers (0: in this process).
    wall_s, cpu_s : float
        Run time of the health analysis (s) and CPU seconds summed over the logs.
    bytes_read : int
    """

    n_logs: int
    n_ok: int
    n_errors: int
    errors: tuple[tuple[str, str], ...]
    imus: tuple[FleetImu, ...]
    workers: int
    wall_s: float
    cpu_s: float
    bytes_read: int

    @property
    def found(self) -> list[FleetImu]:
        """Faulty IMUs flagged as outliers."""
        return [i for i in self.imus if i.faulty and i.outlier]

    @property
    def missed(self) -> list[FleetImu]:
        """Faulty IMUs not flagged."""
        return [i for i in self.imus if i.faulty and not i.outlier]

    @property
    def false_alarms(self) -> list[FleetImu]:
        """Healthy IMUs flagged."""
        return [i for i in self.imus if i.outlier and not i.faulty]


def run(*, seed: int = 2024, quick: bool = False, progress: Progress | None = None) -> FleetResult:
    """Simulate the fleet, run the IMU health analysis, compare the outliers with the truth."""
    from uasnav import fleet
    from uasnav.fleet.output import read_dataset, read_errors
    from uasnav.fleet.simulate import load_truth

    say = progress or (lambda _msg: None)
    vehicles, flights, duration = (3, 2, 40.0) if quick else (5, 4, 120.0)
    with tempfile.TemporaryDirectory(prefix="uasnav-fleet-") as tmp:
        src, out = Path(tmp) / "fleet", Path(tmp) / "health.parquet"
        say(f"fleet: simulating {vehicles} vehicles × {flights} flights")
        fleet.simulate_fleet(src, vehicles, flights, seed=seed % 2**32, duration_s=duration)
        truth = {str(src / f.file): f for f in load_truth(src).files}
        say("fleet: IMU health" + (" in this process" if quick else " on a 2-worker LocalCluster"))
        s = fleet.run(fleet.IMU_HEALTH, [src], out, workers=0 if quick else 2)
        health = read_dataset(out).to_pylist()
        scores = {(r["log_hash"], r["imu"]): r for r in fleet.read_scores(out).to_pylist()}
        errors = tuple(
            (str(Path(r["path"]).relative_to(src)), r["error"]) for r in read_errors(out).to_pylist()
        )

    def mean3(r: dict, stem: str) -> float:
        v = [r[f"{stem}_{a}"] for a in "xyz"]
        return float(np.mean(v)) if all(x is not None for x in v) else float("nan")

    imus = []
    for r in health:
        sc = scores[(r["log_hash"], r["imu"])]
        t = truth[r["path"]]
        imus.append(
            FleetImu(
                file=t.file,
                vehicle=t.vehicle,
                imu_model=r["imu_model"],
                gyro_white=mean3(r, "gyro_random_walk"),
                accel_white=mean3(r, "accel_random_walk"),
                score=float("nan") if sc["score"] is None else float(sc["score"]),
                driver=sc["driver"] or "",
                outlier=bool(sc["outlier"]),
                faulty=t.faulty,
            )
        )
    imus.sort(key=lambda i: i.file)
    return FleetResult(
        n_logs=s.n_logs,
        n_ok=s.n_ok,
        n_errors=s.n_errors,
        errors=errors,
        imus=tuple(imus),
        workers=s.workers,
        wall_s=s.wall_s,
        cpu_s=s.cpu_s,
        bytes_read=s.bytes_read,
    )


__all__ = ["FleetImu", "FleetResult", "run"]
