"""Flight CSV: a telemetry track, one row per fix, header ``t,lat,lon,alt,v_N,v_E,v_D``.

======== ====== ==================================================================
column   unit
======== ====== ==================================================================
``t``    s      time, on the telemetry's clock
``lat``  deg    WGS-84
``lon``  deg    WGS-84
``alt``  m      the telemetry's height (its datum is not stated by the file)
``v_N v_E v_D`` m/s  NED ground velocity
======== ====== ==================================================================

Other columns are ignored; ``#`` comment lines before the header are allowed. The file is read
in chunks by the CSV engine (:mod:`uasnav.io._csvstream`).
"""

from __future__ import annotations

import os
from typing import ClassVar

import numpy as np

from uasnav.errors import DataFormatError
from uasnav.io._csvstream import read_table
from uasnav.io.flight import FIX_LIMITS, Flight
from uasnav.io.formats.base import WholeFileFormat
from uasnav.io.views import Identity

#: Columns of the flight CSV (s, deg, deg, m, then the NED ground velocity in m/s).
FLIGHT_CSV_COLUMNS = ("t", "lat", "lon", "alt", "v_N", "v_E", "v_D")


def is_flight_csv(header: list[str]) -> bool:
    """True if a CSV header (cells, stripped) is the flight CSV layout."""
    return header[: len(FLIGHT_CSV_COLUMNS)] == list(FLIGHT_CSV_COLUMNS) or {"lat", "lon"} <= set(header)


def _select(head: list[str], header_line: int, source: str) -> list[str]:
    missing = [c for c in FLIGHT_CSV_COLUMNS if c not in head]
    if missing:
        raise DataFormatError(
            f"missing column(s) {missing}; need {FLIGHT_CSV_COLUMNS}", path=source, line=header_line
        )
    return list(FLIGHT_CSV_COLUMNS)


def read_flight_csv(path: str | os.PathLike[str]) -> Flight:
    """Read a flight CSV (see the module docs); no mission.

    Raises
    ------
    DataFormatError
        Empty file, missing column, fewer than 2 rows, a non-numeric, missing or non-finite
        cell, a latitude/longitude/altitude outside :data:`FIX_LIMITS`, malformed CSV or text
        that is not UTF-8 (names line and column).
    ResourceLimitError
        If the track would need more memory than the limit (``UASNAV_MAX_MEMORY``).
    """
    source = str(path)
    table = read_table(
        path, lambda h, ln: _select(h, ln, source), what="flight CSV", empty="empty file", min_rows=2
    )
    col = table.columns
    for name in FLIGHT_CSV_COLUMNS[1:4]:
        lo, hi = FIX_LIMITS[name]
        out = np.flatnonzero((col[name] < lo) | (col[name] > hi))
        if out.size:
            raise DataFormatError(
                f"{float(col[name][out[0]])!r} is outside [{lo:g}, {hi:g}]",
                path=source,
                line=table.row_line(int(out[0])),
                column=name,
            )
    vel = np.column_stack([col["v_N"], col["v_E"], col["v_D"]])
    return Flight.from_track(col["t"], col["lat"], col["lon"], col["alt"], vel, source=source)


class FlightCsvFormat(WholeFileFormat):
    """Flight CSV ``t,lat,lon,alt,v_N,v_E,v_D`` (:func:`read_flight_csv`)."""

    name = "flight-csv"
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {"flight": (), "identity": ()}

    def build_flight(self) -> Flight:
        return read_flight_csv(self.path)

    def build_identity(self) -> Identity:
        return Identity(clock="file")


__all__ = ["FLIGHT_CSV_COLUMNS", "FlightCsvFormat", "is_flight_csv", "read_flight_csv"]
