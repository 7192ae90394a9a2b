"""Fleet-scale processing of flight logs on Dask: inventory, IMU health, trajectory elements.

The same per-log code runs in this process (``workers=0``), on a ``distributed.LocalCluster``
(the default) or on an existing Dask cluster (``scheduler=``/``scheduler_file=``)::

    from uasnav import fleet
    fleet.simulate_fleet("fleet", vehicles=5, flights=4)
    s = fleet.run(fleet.IMU_HEALTH, ["fleet"], "health.parquet")      # a LocalCluster
    rows, errors = fleet.read_dataset(s.out), fleet.read_errors(s.out)
    scores = fleet.read_scores(s.out)                                 # anomaly scores

Modules: :mod:`~uasnav.fleet.runner` (the runner, :class:`Analysis`), :mod:`~uasnav.fleet.output`
(layout, manifest, errors table), :mod:`~uasnav.fleet.sources` (finding logs),
:mod:`~uasnav.fleet.deadline` (a log's analysis in a process killed at the per-log deadline),
:mod:`~uasnav.fleet.logs` (reading one log through :mod:`uasnav.io`), and one module per
analysis: :mod:`~uasnav.fleet.scan`, :mod:`~uasnav.fleet.imu_health` (with
:mod:`~uasnav.fleet.anomaly`), :mod:`~uasnav.fleet.elements`; :mod:`~uasnav.fleet.simulate`
writes synthetic fleets and :mod:`~uasnav.fleet.html` the ``--report`` page.
"""

from uasnav._extras import require

# the whole package writes and reads Parquet on Dask: one line naming the extra, before any import
require("fleet", "uasnav fleet")

from uasnav.fleet.anomaly import read_scores  # noqa: E402
from uasnav.fleet.imu_health import IMU_HEALTH  # noqa: E402
from uasnav.fleet.output import read_dataset, read_errors  # noqa: E402
from uasnav.fleet.runner import Analysis, LogRows, RunSummary, local_cluster, run  # noqa: E402
from uasnav.fleet.scan import SCAN  # noqa: E402
from uasnav.fleet.simulate import simulate_fleet  # noqa: E402

__all__ = [
    "IMU_HEALTH",
    "SCAN",
    "Analysis",
    "LogRows",
    "RunSummary",
    "local_cluster",
    "read_dataset",
    "read_errors",
    "read_scores",
    "run",
    "simulate_fleet",
]
