"""The thesis' experiments, computed: one module per chapter topic.

Each module has a ``run(*, seed=2024, quick=False, progress=None)`` function that performs the
topic's experiments on simulated or embedded data and returns a frozen dataclass of numbers and
arrays — no HTML and no matplotlib. The report (:mod:`uasnav.report`) renders those results
into paragraphs, tables and figures; tests call these modules directly.

The published numbers the results are compared with live once, in :mod:`uasnav.experiments.thesis`.

Modules: ``allan``, ``attitude``, ``simulator``, ``calibration``, ``zupt``, ``redundancy``,
``ardupilot`` (real ArduPilot logs, used by tests and benchmarks, never by the report),
``trajectory``, ``mission``.
"""
