"""ArduPilot DataFlash (``.bin``): one pymavlink pass per command for the message types its
views need.

Views and their messages (:attr:`DataflashFormat.SOURCES`): ``imus`` (``IMU``/``IMU2``/``IMU3``,
:func:`uasnav.io.dataflash.read_dataflash`), ``nav`` (:func:`read_dataflash_nav`), ``flight``
(:func:`uasnav.io.dataflash.read_dataflash_flight`), ``plan`` (``CMD``), ``params``/``limits``
(``PARM``), ``modes`` (``MODE``), ``identity`` (``MSG`` firmware and board lines, ``GPS`` week).

Format rules kept here: the GPS delay (fix times moved back by :data:`ARDUPILOT_GPS_DELAY_S`),
accuracies from HDOP, the EKF origin (``ORGN``), the declination parameter (``COMPASS_DEC``
used only with ``COMPASS_AUTODEC`` 0) and the height datum (AMSL: ``GPS.Alt`` and ``ORGN.Alt``
are both above mean sea level as the receiver models it).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import DataFormatError, InputError
from uasnav.geo.datum import HeightDatum
from uasnav.geo.frames import ned_to_geodetic
from uasnav.io.dataflash import (
    IMU_TYPES,
    read_dataflash,
    read_dataflash_flight,
    read_dataflash_identity,
    read_dataflash_messages,
)
from uasnav.io.flight import BaroData, Flight, GnssData, MagData, Trajectory, strictly_increasing
from uasnav.io.formats._scan import MavlinkScan
from uasnav.io.formats.base import LogFormat
from uasnav.io.plan_formats.logs import read_dataflash_plan
from uasnav.io.views import Identity, ModeTimeline, changes

FloatArray = NDArray[np.float64]

#: The messages of the navigation data.
NAV_TYPES = ("GPS", "BARO", "MAG", "XKF1", "NKF1", "EKF1", "AHR2", "ATT", "ORGN")
#: ArduCopter's mode numbers (``MODE.Mode``).
COPTER_MODES = {
    0: "STABILIZE", 1: "ACRO", 2: "ALT_HOLD", 3: "AUTO", 4: "GUIDED", 5: "LOITER", 6: "RTL",
    7: "CIRCLE", 9: "LAND", 11: "DRIFT", 13: "SPORT", 14: "FLIP", 15: "AUTOTUNE", 16: "POSHOLD",
    17: "BRAKE", 18: "THROW", 19: "AVOID_ADSB", 20: "GUIDED_NOGPS", 21: "SMART_RTL",
}  # fmt: skip
_FIRMWARE = re.compile(r"^(?:APM:|Ardu)(\w+) V(\d+\.\d+(?:\.\d+)?\S*)(?: \((\w+)\))?")
_BOARD_ID = re.compile(r"^(\S+) ([0-9A-F]{8} [0-9A-F]{8} [0-9A-F]{8})$")


#: ArduPilot's GPS message has no accuracy fields in older logs: σ_H = HDOP × this UERE (m),
#: σ_V = 1.5 σ_H, and the speed accuracy below. Stated, not measured: a u-blox receiver with
#: HDOP ≈ 1.5 typically reaches 1–3 m.
ARDUPILOT_UERE_M = 1.0
ARDUPILOT_SPEED_ACC_M_S = 0.3
#: ArduPilot logs a GPS message when it arrives; the fix is valid this long before (s): the
#: autopilot's own default ``EKF_GPS_DELAY`` / ``GPS_DELAY_MS`` of 220 ms.
ARDUPILOT_GPS_DELAY_S = 0.22


def _pick(
    tables: dict[str, dict[str, FloatArray]], names: tuple[str, ...]
) -> tuple[str, dict[str, FloatArray]] | None:
    for n in names:
        if n in tables and tables[n]["t"].size >= 2:
            return n, tables[n]
    return None


def _declination_meta(path: Any, gp: dict[str, FloatArray], first: int) -> dict[str, Any]:
    """``declination_deg``/``declination_source`` from ``PARM`` ``COMPASS_DEC`` (radians) when
    the autopilot used it (``COMPASS_AUTODEC`` 0: with auto-declination on it takes its own
    table's value at run time and the logged parameter is not that value), and ``utc_year``
    (decimal year) from the ``GPS`` week and time of week of fix ``first``."""
    from uasnav.io._mavlink import messages, reading
    from uasnav.io.gpstime import decimal_year, gps_week_ms_to_utc

    p = Path(path)
    params: dict[str, float] = {}
    with reading(p) as (conn, _):
        for m in messages(conn, ["PARM"], p, "DataFlash"):
            name = str(m.Name).rstrip("\x00")
            if name in ("COMPASS_DEC", "COMPASS_AUTODEC"):
                params[name] = float(m.Value)  # the last value logged wins
    meta: dict[str, Any] = {}
    dec = params.get("COMPASS_DEC")
    if dec is not None and math.isfinite(dec) and params.get("COMPASS_AUTODEC", 0.0) == 0.0:
        meta["declination_deg"] = math.degrees(dec)
        meta["declination_source"] = "log: PARM COMPASS_DEC (COMPASS_AUTODEC = 0)"
    week = gp.get("GWk", gp.get("Week"))
    tow = gp.get("GMS", gp.get("TimeMS"))
    if week is not None and tow is not None:
        w, ms = float(week[first]), float(tow[first])
        if math.isfinite(w) and math.isfinite(ms) and 1000 < w < 10000 and 0 <= ms < 604_800_000:
            meta["utc_year"] = decimal_year(gps_week_ms_to_utc(w, ms))
    return meta


def read_dataflash_nav(path: str | Any, imu: str | None = None) -> Flight:
    """Navigation data of an ArduPilot DataFlash log: every IMU (``IMU``/``IMU2``/``IMU3``
    with temperature), ``GPS`` (fixes with ``Status`` ≥ 3; time from its ``T`` field, the
    log clock, when ``TimeMS`` is GPS time of week), ``BARO`` (``Alt``), ``MAG`` (field minus
    nothing: the logged ``MagX/Y/Z`` are already offset-corrected), and the autopilot's
    estimate from ``XKF1``/``NKF1``/``EKF1`` (``PN/PE/PD`` from the origin, taken as the first
    3-D fix, ``VN/VE/VD``, ``Roll/Pitch/Yaw``), else ``AHR2``.

    Heights are AMSL throughout: the GPS ``Alt`` (the receiver's AMSL; the message carries no
    ellipsoidal height) and the estimate from the EKF origin ``ORGN`` (AMSL) when logged, else
    the first 3-D fix. Accuracies from HDOP (see
    :data:`ARDUPILOT_UERE_M`); fix times moved back by the GPS delay
    (:data:`ARDUPILOT_GPS_DELAY_S`).

    Raises
    ------
    DataFormatError
        No IMU, no GPS message, or fewer than 2 fixes with ``Status`` ≥ 3 (named).
    """
    imus = read_dataflash(path)
    tables = read_dataflash_messages(path, NAV_TYPES)
    if "GPS" not in tables:
        raise DataFormatError(
            "no GPS message: the GNSS/INS filter needs GNSS fixes", path=str(path), column="GPS"
        )
    gp = tables["GPS"]
    t_field = "T" if "T" in gp and np.all(np.isfinite(gp["T"])) and gp["T"].max() > 0 else None
    t = gp["T"] * 1e-3 if t_field else gp["t"]
    status = gp.get("Status", np.full(t.size, 3.0))
    ok = (status >= 3) & np.isfinite(gp["Lat"]) & np.isfinite(gp["Lng"]) & (np.abs(gp["Lat"]) > 1e-6)
    t, ok = t[ok], np.flatnonzero(ok)
    keep = strictly_increasing(t)
    t, ok = t[keep], ok[keep]
    if t.size < 2:
        raise DataFormatError(
            "GPS: fewer than 2 fixes with Status >= 3 (3-D fix)", path=str(path), column="GPS.Status"
        )
    spd, crs = gp["Spd"][ok], np.radians(gp["GCrs"][ok])
    vz = gp["VZ"][ok] if "VZ" in gp else np.zeros(t.size)
    hdop = gp["HDop"][ok] if "HDop" in gp else np.full(t.size, 1.5)
    h_acc = np.maximum(np.nan_to_num(hdop, nan=5.0), 0.5) * ARDUPILOT_UERE_M
    gnss = GnssData(
        t - ARDUPILOT_GPS_DELAY_S,
        gp["Lat"][ok],
        gp["Lng"][ok],
        gp["Alt"][ok],
        np.column_stack([spd * np.cos(crs), spd * np.sin(crs), vz]),
        h_acc,
        1.5 * h_acc,
        np.full(t.size, ARDUPILOT_SPEED_ACC_M_S),
        alt_datum=HeightDatum.AMSL,
    )
    baro = None
    if "BARO" in tables and tables["BARO"]["t"].size >= 2:
        b = tables["BARO"]
        k = strictly_increasing(b["t"]) & np.isfinite(b["Alt"])
        baro = BaroData(b["t"][k], b["Alt"][k])
    mag = None
    if "MAG" in tables and tables["MAG"]["t"].size >= 2:
        m = tables["MAG"]
        k = strictly_increasing(m["t"])
        fld = np.column_stack([m["MagX"], m["MagY"], m["MagZ"]])[k]
        k2 = np.all(np.isfinite(fld), axis=1) & (np.linalg.norm(fld, axis=1) > 0)
        mag = MagData(m["t"][k][k2], fld[k2])
    ref = None
    ekf = _pick(tables, ("XKF1", "NKF1", "EKF1"))
    if ekf is not None:
        name, e = ekf
        lat0, lon0, alt0 = float(gnss.lat[0]), float(gnss.lon[0]), float(gnss.alt[0])
        origin = "first 3-D fix"
        og = tables.get("ORGN")
        if og is not None and {"Lat", "Lng", "Alt"} <= set(og):
            # the EKF origin as the autopilot logged it (Type 0; Type 1 is the home position)
            k0 = np.flatnonzero((og.get("Type", np.zeros(og["t"].size)) == 0) & (np.abs(og["Lat"]) > 1e-6))
            if k0.size:
                lat0, lon0, alt0 = (float(og[f][k0[-1]]) for f in ("Lat", "Lng", "Alt"))
                origin = "ORGN"
        k = strictly_increasing(e["t"])
        lat, lon, alt = ned_to_geodetic(e["PN"][k], e["PE"][k], e["PD"][k], lat0, lon0, alt0)
        ref = Trajectory(
            e["t"][k],
            np.asarray(lat, dtype=np.float64),
            np.asarray(lon, dtype=np.float64),
            np.asarray(alt, dtype=np.float64),
            np.column_stack([e["VN"], e["VE"], e["VD"]])[k],
            np.column_stack([e["Roll"], e["Pitch"], e["Yaw"]])[k],
            name=f"ArduPilot EKF ({name}; origin = {origin})",
            alt_datum=HeightDatum.AMSL,
        )
    elif "AHR2" in tables:
        a = tables["AHR2"]
        k = strictly_increasing(a["t"]) & (np.abs(a["Lat"]) > 1e-6)
        if k.sum() >= 2:
            ref = Trajectory(
                a["t"][k],
                a["Lat"][k],
                a["Lng"][k],
                a["Alt"][k],
                None,
                np.column_stack([a["Roll"], a["Pitch"], a["Yaw"]])[k],
                name="ArduPilot AHR2",
                alt_datum=HeightDatum.AMSL,
            )
    key = imu or next(iter(imus))
    if key not in imus:
        raise InputError(f"imu: {key!r} not in the log (has {', '.join(imus)})")
    return Flight(
        imus[key],
        gnss,
        baro,
        mag,
        reference=ref,
        imus=imus,
        meta={
            "source": str(path),
            "format": "ardupilot-dataflash",
            "imu": key,
            **_declination_meta(path, gp, int(ok[0])),
        },
    )


class DataflashFormat(LogFormat):
    """ArduPilot DataFlash (see the module docs)."""

    name = "ardupilot-dataflash"
    SCANNER = MavlinkScan
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {
        "imus": IMU_TYPES,
        "imu": IMU_TYPES,
        "nav": (*IMU_TYPES, *NAV_TYPES, "PARM"),
        "flight": ("GPS", "CMD", "MSG", "XKF2", "NKF2", "EKF2"),
        "plan": ("CMD",),
        "params": ("PARM",),
        "limits": ("PARM",),
        "modes": ("MODE", "MSG"),
        "identity": ("MSG", "GPS"),
    }
    READERS: ClassVar[dict[str, Callable[[Path], Any]]] = {
        "imus": read_dataflash,
        "nav": read_dataflash_nav,
        "flight": read_dataflash_flight,
        "plan": read_dataflash_plan,
    }

    def build_params(self) -> dict[str, float]:
        from uasnav.io._mavlink import messages, reading

        out: dict[str, float] = {}
        with reading(self.path) as (conn, _):
            for m in messages(conn, ["PARM"], self.path, "DataFlash"):
                out[str(m.Name).rstrip("\x00")] = float(m.Value)  # the last value logged wins
        return out

    def _texts(self) -> list[str]:
        from uasnav.io._mavlink import messages, reading

        with reading(self.path) as (conn, _):
            msgs = messages(conn, ["MSG"], self.path, "DataFlash")
            return [str(m.to_dict().get("Message", "")).strip() for m in msgs]

    def build_modes(self) -> ModeTimeline:
        copter = any(_vehicle(s) == "Copter" for s in self._texts())
        modes = read_dataflash_messages(self.path, ["MODE"]).get("MODE")
        if modes is None or "Mode" not in modes:
            return ModeTimeline(np.zeros(0), (), "MODE")
        names = [
            (COPTER_MODES.get(int(m), f"MODE_{int(m)}") if copter else f"MODE_{int(m)}")
            for m in modes["Mode"]
        ]
        return changes(modes["t"], names, "MODE.Mode")

    def build_identity(self) -> Identity:
        fields: dict[str, Any] = {"autopilot": "ArduPilot", "clock": "boot"}
        for text in self._texts():
            fw = _FIRMWARE.match(text)
            if fw and "firmware_version" not in fields:
                fields["vehicle_type"] = "Ardu" + fw.group(1)
                fields["firmware_version"] = fw.group(2)
                if fw.group(3):
                    fields["firmware_git"] = fw.group(3)
            board = _BOARD_ID.match(text)
            if board and "board" not in fields:
                fields["board"], fields["vehicle_id"] = board.group(1), board.group(2)
        ident = read_dataflash_identity(self.path)
        if "boot_utc" in ident:
            fields["utc_at_zero"] = ident["boot_utc"]
            fields["leap_seconds"] = ident.get("leap_seconds")
        return Identity(**fields)


def _vehicle(text: str) -> str | None:
    fw = _FIRMWARE.match(text)
    return None if fw is None else fw.group(1)


__all__ = [
    "ARDUPILOT_GPS_DELAY_S",
    "ARDUPILOT_SPEED_ACC_M_S",
    "ARDUPILOT_UERE_M",
    "DataflashFormat",
    "read_dataflash_nav",
]
