"""Text and array logs read whole: CSV v1 (+ a GNSS CSV given separately), the x-io CSV, the
flight CSV and ``.npz``. Which CSV a file is follows its header (:func:`csv_kind`).

Heights: the GNSS CSV's ``alt`` is ellipsoidal (:mod:`uasnav.io.gnss_csv`); the flight CSV's
``alt`` is the telemetry's height (not stated by the file).
"""

from __future__ import annotations

import os
from abc import abstractmethod
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from uasnav.errors import DataFormatError, InputError
from uasnav.imu import ImuLog
from uasnav.io._text import csv_rows, numeric_rows, read_text, split_lines
from uasnav.io.flight import FIX_LIMITS, Flight, GnssData, MagData
from uasnav.io.formats.base import WholeFileFormat
from uasnav.io.views import Identity

#: Columns of the flight CSV (s, deg, deg, m, then the NED ground velocity in m/s).
FLIGHT_CSV_COLUMNS = ("t", "lat", "lon", "alt", "v_N", "v_E", "v_D")


def csv_kind(path: str | Path) -> str:
    """``csv-v1``, ``xio-csv`` or ``flight-csv`` from the first non-comment line of a CSV file.

    Raises
    ------
    DataFormatError
        Missing file, a directory, or unreadable.
    """
    from uasnav.io.xio import is_xio_csv

    p = Path(path)
    try:
        with open(p, "rb") as fh:
            for _ in range(1000):
                raw = fh.readline(4096)  # a bounded peek, whatever the file
                if not raw:
                    break
                line = raw.decode("utf-8", errors="replace").lstrip("\ufeff").strip()
                if not line or line.startswith("#"):
                    continue
                if is_xio_csv(line):
                    return "xio-csv"
                cols = [c.strip() for c in line.split(",")]
                if cols[: len(FLIGHT_CSV_COLUMNS)] == list(FLIGHT_CSV_COLUMNS) or {"lat", "lon"} <= set(cols):
                    return "flight-csv"
                return "csv-v1"
    except FileNotFoundError:
        raise DataFormatError("no such file", path=str(p)) from None
    except IsADirectoryError:
        raise DataFormatError("is a directory, not a file", path=str(p)) from None
    except OSError as e:
        raise DataFormatError(f"cannot read ({e.strerror or e})", path=str(p)) from None
    return "csv-v1"


class ImuFileFormat(WholeFileFormat):
    """An IMU log read whole by one reader (:meth:`read_imu`), once, then cached."""

    @abstractmethod
    def read_imu(self) -> ImuLog:
        """The file's IMU log."""

    def build_imu(self) -> ImuLog:
        cached = self.options.get("_imu")
        if cached is None:
            cached = self.options["_imu"] = self.read_imu()
        return cached  # type: ignore[no-any-return]

    def build_imus(self) -> dict[str, Any]:
        return {"imu0": self.build_imu()}

    def build_identity(self) -> Identity:
        meta = self.build_imu().meta
        return Identity(vehicle_id=meta.get("vehicle"), board=meta.get("hardware"), clock="file")


class CsvV1Format(ImuFileFormat):
    """CSV v1 IMU log (:func:`uasnav.io.csv_v1.read_csv_v1`); ``nav`` with the GNSS CSV given
    as the option ``gnss`` (``mx my mz`` become the magnetometer when present)."""

    name = "csv-v1"
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {"imus": (), "imu": (), "nav": (), "identity": ()}

    def read_imu(self) -> ImuLog:
        from uasnav.io.csv_v1 import read_csv_v1

        return read_csv_v1(self.path)

    def stream(self) -> Any:
        """The data rows in chunks, for consumers that stream
        (:func:`uasnav.io.csv_v1.open_csv_v1`: block means while reading)."""
        from uasnav.io.csv_v1 import open_csv_v1

        return open_csv_v1(self.path)

    def build_nav(self) -> Flight:
        gnss = self.options.get("gnss")
        if gnss is None:
            raise InputError(
                f"{self.path}: a CSV IMU log needs --gnss GNSS.csv (t,lat,lon,alt,vn,ve,vd,h_acc,v_acc,s_acc)"
            )
        if not isinstance(gnss, GnssData):
            from uasnav.io.gnss_csv import read_gnss_csv

            gnss = read_gnss_csv(gnss)
        imu = self.build_imu()
        mag = MagData(imu.t, imu.mag) if imu.mag is not None else None
        meta = {"source": str(self.path), "format": "csv-v1", "imu": "IMU"}
        return Flight(imu, gnss, None, mag, imus={"IMU": imu}, meta=meta)


class XioFormat(ImuFileFormat):
    """x-io Technologies CSV (:func:`uasnav.io.xio.read_xio_csv`)."""

    name = "xio-csv"
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {"imus": (), "imu": (), "identity": ()}

    def read_imu(self) -> ImuLog:
        from uasnav.io.xio import read_xio_csv

        return read_xio_csv(self.path)


class NpzFormat(ImuFileFormat):
    """uasnav / ADIS ``.npz`` IMU arrays (:func:`uasnav.io.npz.read_npz`)."""

    name = "npz"
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {"imus": (), "imu": (), "identity": ()}

    def read_imu(self) -> ImuLog:
        from uasnav.io.npz import read_npz

        return read_npz(self.path)


def read_flight_csv(path: str | os.PathLike[str]) -> Flight:
    """Read a flight CSV: header ``t,lat,lon,alt,v_N,v_E,v_D`` (s, deg, deg, m, m/s NED), no mission.

    Other columns are ignored.

    Raises
    ------
    DataFormatError
        Empty file, missing column, fewer than 2 rows, a non-numeric, missing or non-finite
        cell, a latitude/longitude/altitude outside :data:`FIX_LIMITS`, malformed CSV or text
        that is not UTF-8 (names line and column).
    """
    source = str(path)
    lines = split_lines(read_text(path))
    first = next(csv_rows(lines, 0, source), None)
    if first is None:
        raise DataFormatError("empty file", path=source)
    header_line, cells = first
    head = [h.strip() for h in cells]
    missing = [c for c in FLIGHT_CSV_COLUMNS if c not in head]
    if missing:
        raise DataFormatError(
            f"missing column(s) {missing}; need {FLIGHT_CSV_COLUMNS}", path=source, line=header_line
        )
    data, row_lines = numeric_rows(lines, header_line, source, head, FLIGHT_CSV_COLUMNS)
    for j, name in enumerate(FLIGHT_CSV_COLUMNS[1:4], start=1):
        lo, hi = FIX_LIMITS[name]
        out = np.flatnonzero((data[:, j] < lo) | (data[:, j] > hi))
        if out.size:
            raise DataFormatError(
                f"{float(data[out[0], j])!r} is outside [{lo:g}, {hi:g}]",
                path=source,
                line=row_lines[out[0]],
                column=name,
            )
    return Flight.from_track(data[:, 0], data[:, 1], data[:, 2], data[:, 3], data[:, 4:7], source=source)


class FlightCsvFormat(WholeFileFormat):
    """Flight CSV ``t,lat,lon,alt,v_N,v_E,v_D`` (:func:`read_flight_csv`)."""

    name = "flight-csv"
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {"flight": (), "identity": ()}

    def build_flight(self) -> Flight:
        return read_flight_csv(self.path)

    def build_identity(self) -> Identity:
        return Identity(clock="file")


__all__ = [
    "FLIGHT_CSV_COLUMNS",
    "CsvV1Format",
    "FlightCsvFormat",
    "ImuFileFormat",
    "NpzFormat",
    "XioFormat",
    "csv_kind",
    "read_flight_csv",
]
