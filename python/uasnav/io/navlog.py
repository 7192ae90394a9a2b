"""One entry point for the navigation data of any log: :func:`read_nav` picks the reader
(:mod:`uasnav.io.navdata` for DataFlash, ULog and CSV v1; :mod:`uasnav.io.tlog`;
:mod:`uasnav.io.alfa`) from the path and adds a GNSS CSV (:mod:`uasnav.io.gnss_csv`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from uasnav.errors import InputError
from uasnav.io.alfa import read_alfa_folder
from uasnav.io.gnss_csv import read_gnss_csv
from uasnav.io.navdata import Flight, read_csv_nav, read_dataflash_nav, read_ulog_nav
from uasnav.io.tlog import read_tlog_nav


def read_nav(path: str | Any, *, gnss_csv: str | None = None) -> Flight:
    """The navigation data of a log, by extension: ``.bin`` (DataFlash), ``.ulg`` (ULog),
    ``.tlog`` (MAVLink), ``.csv`` (CSV v1, with ``gnss_csv`` required), or an ALFA ROS-topic CSV
    folder. ``gnss_csv`` replaces the log's own GNSS when given.

    Raises
    ------
    InputError
        Unknown extension, or a CSV log without ``gnss_csv``.
    """
    p = Path(path)
    gnss = None
    if gnss_csv is not None:
        gnss = read_gnss_csv(gnss_csv)
    if p.is_dir():
        f = read_alfa_folder(p)
    else:
        ext = p.suffix.lower()
        if ext == ".bin":
            f = read_dataflash_nav(p)
        elif ext == ".ulg":
            f = read_ulog_nav(p)
        elif ext == ".tlog":
            f = read_tlog_nav(p)
        elif ext in (".csv", ".txt"):
            if gnss is None:
                raise InputError(
                    f"{p}: a CSV IMU log needs --gnss GNSS.csv (t,lat,lon,alt,vn,ve,vd,h_acc,v_acc,s_acc)"
                )
            return read_csv_nav(p, gnss)
        else:
            raise InputError(
                f"{p}: unknown log type {ext!r} (expected .ulg, .bin, .tlog, .csv or an ALFA folder)"
            )
    if gnss is not None:
        f = Flight(f.imu, gnss, f.baro, f.mag, f.reference, f.truth, f.imus, f.airborne, f.meta)
    return f
