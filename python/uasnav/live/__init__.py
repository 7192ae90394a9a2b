"""uasnav on a live MAVLink telemetry stream.

- :mod:`uasnav.live.source` — a flight log as the MAVLink messages a ground station receives
  (a ``.tlog`` as recorded; DataFlash and ULog converted from their :func:`uasnav.io.open_log`
  views), with the log's timing.
- :mod:`uasnav.live.replay` — sends those messages over UDP in recorded timing (``uasnav replay``).
- :mod:`uasnav.live.stream` — receiving: pymavlink connections, duplicates, reordering and
  telemetry loss judged on the vehicle's clock.
- :mod:`uasnav.live.conformance` — ASTM F3548 conformance monitoring of operational intents
  (``uasnav monitor``).
- :mod:`uasnav.live.nav` — the GNSS/INS filter stepped message by message (``uasnav nav --live``
  and ``--causal``).
"""
