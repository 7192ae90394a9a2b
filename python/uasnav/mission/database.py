"""The UAS and camera database (thesis Table 21, extended) as column arrays.

Columns are numpy arrays so that feasibility tests and scoring run vectorised over the whole
database (10⁴ UAS × 10³ cameras). Units are in the field names (g, min, m, m/s, USD, deg, px).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from uasnav.mission.loading import load_document


def _rain_capable(ip: str | None, rain: str | None) -> bool:
    # IEC 60529: second digit 3 = spraying water, the lowest rating meaningful against rain.
    if rain is not None:
        return rain.strip() == "true" or rain.strip() == "1"
    return ip is not None and ip[3].isdigit() and int(ip[3]) >= 3


@dataclass(frozen=True)
class UasTable:
    """UAS columns; one entry per aircraft, all arrays shape (n,)."""

    ids: list[str]
    producers: list[str]
    names: list[str]
    types: list[str]
    cost_usd: np.ndarray
    span_m: np.ndarray
    mass_g: np.ndarray
    max_takeoff_g: np.ndarray  # NaN where not published
    endurance_min: np.ndarray
    payload_g: np.ndarray
    max_speed_ms: np.ndarray
    max_altitude_m: np.ndarray
    max_range_m: np.ndarray
    eu_class: list[str | None]
    rain: np.ndarray  # bool
    sources: list[str]
    estimated: list[frozenset[str]]
    #: Equipment tokens per UAS as delivered (database.xml ``<equipment has>``); None where the
    #: entry has no reviewed equipment record.
    equipment: list[frozenset[str] | None] = field(default_factory=list)
    #: The document each equipment record comes from (None where there is no record).
    equipment_sources: list[str | None] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.ids)

    def label(self, i: int) -> str:
        """ "Producer Name" of entry ``i``."""
        return f"{self.producers[i]} {self.names[i]}"

    def has(self, token: str) -> np.ndarray:
        """Boolean mask, shape (n,): UAS whose equipment record lists ``token`` (False where
        there is no record)."""
        eq = self.equipment or [None] * len(self)
        return np.array([e is not None and token in e for e in eq], dtype=bool)


@dataclass(frozen=True)
class CameraTable:
    """Camera columns; one entry per camera, all arrays shape (n,)."""

    ids: list[str]
    producers: list[str]
    names: list[str]
    types: list[str]
    cost_usd: np.ndarray
    mass_g: np.ndarray
    hfov_deg: np.ndarray
    resolution_w_px: np.ndarray
    resolution_h_px: np.ndarray
    sensor_w_mm: np.ndarray  # NaN where unknown
    focal_mm: np.ndarray  # NaN where unknown
    bands: list[str]
    sources: list[str]
    estimated: list[frozenset[str]]
    capture_interval_s: np.ndarray  # shortest interval between two captures, s; NaN where unknown
    exposure_s: np.ndarray  # fixed exposure, s; NaN where unknown (automatic exposure)

    def __len__(self) -> int:
        return len(self.ids)

    def label(self, i: int) -> str:
        """ "Producer Name" of entry ``i``."""
        return f"{self.producers[i]} {self.names[i]}"

    @property
    def ifov_deg(self) -> np.ndarray:
        """Angular resolution (deg/px): HFOV divided by the pixels across (thesis §5.2.3.5)."""
        return self.hfov_deg / self.resolution_w_px


@dataclass(frozen=True)
class Database:
    """UAS and cameras loaded from one ``<database>`` document."""

    uas: UasTable
    cameras: CameraTable
    where: str


def _num(el, tag: str) -> float:
    txt = el.findtext(tag)
    return float(txt) if txt is not None else float("nan")


def load_database(source: str | os.PathLike | None = None, **fetch_kw) -> Database:
    """Load and validate a database from a path, an http(s) URL or the shipped default.

    ``fetch_kw`` are passed to :func:`uasnav.mission.loading.fetch` (``timeout_s``,
    ``max_bytes``, ``cache_dir`` …).
    """
    tree, where = load_document(source, "database", default="database.xml", **fetch_kw)
    root = tree.getroot()
    us = root.findall("uas-list/uas")
    cs = root.findall("camera-list/camera")

    def col(items, tag):
        return np.array([_num(e, tag) for e in items], dtype=float)

    def est(e):
        return frozenset((e.get("estimated") or "").split())

    def common(items):
        """The columns every equipment table has (identity, cost, provenance)."""
        return {
            "ids": [e.get("id") for e in items],
            "producers": [e.findtext("producer") for e in items],
            "names": [e.findtext("name") for e in items],
            "types": [e.get("type") for e in items],
            "cost_usd": col(items, "cost_usd"),
            "sources": [e.findtext("source") for e in items],
            "estimated": [est(e) for e in items],
        }

    uas = UasTable(
        **common(us),
        span_m=col(us, "span_m"),
        mass_g=col(us, "mass_g"),
        max_takeoff_g=col(us, "max_takeoff_g"),
        endurance_min=col(us, "endurance_min"),
        payload_g=col(us, "payload_g"),
        max_speed_ms=col(us, "max_speed_ms"),
        max_altitude_m=col(us, "max_altitude_m"),
        max_range_m=col(us, "max_range_m"),
        eu_class=[e.findtext("eu_class") for e in us],
        rain=np.array([_rain_capable(e.findtext("ip_rating"), e.findtext("rain")) for e in us], dtype=bool),
        equipment=[
            frozenset(q.get("has").split()) if (q := e.find("equipment")) is not None else None for e in us
        ],
        equipment_sources=[q.get("source") if (q := e.find("equipment")) is not None else None for e in us],
    )
    cams = CameraTable(
        **common(cs),
        mass_g=col(cs, "mass_g"),
        hfov_deg=col(cs, "hfov_deg"),
        resolution_w_px=col(cs, "resolution_w_px"),
        resolution_h_px=col(cs, "resolution_h_px"),
        sensor_w_mm=col(cs, "sensor_w_mm"),
        focal_mm=col(cs, "focal_mm"),
        bands=[e.findtext("bands") or "" for e in cs],
        capture_interval_s=col(cs, "capture_interval_s"),
        exposure_s=col(cs, "exposure_s"),
    )
    return Database(uas, cams, where)
