"""GNSS CSV: one fix per row, header ``t,lat,lon,alt,vn,ve,vd,h_acc,v_acc,s_acc``.

=========== ====== =====================================================
column      unit
=========== ====== =====================================================
``t``       s      fix time, on the IMU log's clock, strictly increasing
``lat lon`` deg    WGS-84
``alt``     m      WGS-84 ellipsoidal height
``vn ve vd`` m/s   NED velocity
``h_acc``   m      reported 1σ horizontal accuracy (> 0)
``v_acc``   m      reported 1σ vertical accuracy (> 0)
``s_acc``   m/s    reported 1σ speed accuracy (> 0)
=========== ====== =====================================================

``#`` comment lines before the header are allowed; other columns are ignored. The file is read
in chunks by the CSV engine (:mod:`uasnav.io._csvstream`), with the errors of a numeric table
(:func:`uasnav.io.table.read_csv_table`: quotes, non-numeric and infinite cells, wrong widths).
"""

from __future__ import annotations

import os

import numpy as np

from uasnav.atomicfile import atomic_open
from uasnav.errors import DataFormatError, InputError
from uasnav.io._csvstream import read_table
from uasnav.io.flight import GnssData
from uasnav.io.table import check_header, write_rows

#: The columns, in order.
GNSS_COLUMNS = ("t", "lat", "lon", "alt", "vn", "ve", "vd", "h_acc", "v_acc", "s_acc")


def read_gnss_csv(path: str | os.PathLike[str]) -> GnssData:
    """Read a GNSS CSV (see the module docs).

    Raises
    ------
    DataFormatError
        Unreadable or malformed file, a missing column (named), fewer than 1 fix, or values
        :class:`~uasnav.io.flight.GnssData` refuses (time not increasing, |lat| > 90°,
        accuracies ≤ 0), with the file named.
    """

    def select(header: list[str], header_line: int) -> list[str]:
        check_header(header, header_line, str(path))
        missing = [c for c in GNSS_COLUMNS if c not in header]
        if missing:
            raise DataFormatError(
                f"GNSS CSV: missing column(s) {', '.join(missing)}", path=str(path), column=missing[0]
            )
        return list(GNSS_COLUMNS)

    cols = read_table(path, select, what="GNSS CSV", exact_width=True, nan_ok=True).columns
    if len(cols["t"]) == 0:
        raise DataFormatError("GNSS CSV: no fixes (a header only)", path=str(path))
    try:
        return GnssData(
            cols["t"],
            cols["lat"],
            cols["lon"],
            cols["alt"],
            np.column_stack([cols["vn"], cols["ve"], cols["vd"]]),
            cols["h_acc"],
            cols["v_acc"],
            cols["s_acc"],
        )
    except InputError as e:
        raise DataFormatError(str(e), path=str(path)) from None


def write_gnss_csv(path: str | os.PathLike[str], gnss: GnssData) -> None:
    """Write ``gnss`` as a GNSS CSV (17 significant digits: exact round trip), atomically."""
    table = np.column_stack(
        [gnss.t, gnss.lat, gnss.lon, gnss.alt, gnss.vel, gnss.h_acc, gnss.v_acc, gnss.s_acc]
    )
    with atomic_open(path, "w") as fh:
        fh.write(",".join(GNSS_COLUMNS) + "\n")
        write_rows(fh, table)


__all__ = ["GNSS_COLUMNS", "read_gnss_csv", "write_gnss_csv"]
