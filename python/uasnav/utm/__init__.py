"""UTM building blocks: ASTM F3548 operational intents from mission plans, and strategic
deconfliction of many intents with a space-time index.

- :mod:`uasnav.utm.deconflict` — :func:`deconflict`, :func:`encounters` (Rust index),
  :func:`earliest_delays`.
- :mod:`uasnav.utm.volumes` — intents as arrays in a local plane (:class:`VolumeArrays`).
- :mod:`uasnav.utm.strtree` — the same search with shapely's STRtree (reference).
- Reading and writing intents: :mod:`uasnav.io.operational_intent` (F3548 JSON, typed with
  ``uas-standards``) and :mod:`uasnav.io.interuss` (InterUSS flight-intent templates).
"""

from uasnav.utm.deconflict import (
    Conflict,
    Deconfliction,
    NearMiss,
    deconflict,
    earliest_delays,
    encounters,
)
from uasnav.utm.volumes import VolumeArrays, volume_arrays

__all__ = [
    "Conflict",
    "Deconfliction",
    "NearMiss",
    "VolumeArrays",
    "deconflict",
    "earliest_delays",
    "encounters",
    "volume_arrays",
]
