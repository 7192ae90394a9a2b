"""Navigation-track files (uasnav.io.track): exact bytes of TRACK.csv, KML and GeoJSON for a
hand-made track, and the plot's local NED projection against pymap3d."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pytest

from uasnav.io import track


@dataclass
class Track:
    t: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    alt: np.ndarray
    vel: np.ndarray
    euler_deg: np.ndarray
    gyro_bias: np.ndarray
    accel_bias: np.ndarray
    hpl: np.ndarray
    vpl: np.ndarray
    gnss_used: np.ndarray
    excluded_fixes: list[dict[str, Any]] = field(default_factory=list)
    alerts: list[dict[str, Any]] = field(default_factory=list)


def _track() -> Track:
    n = 3
    return Track(
        t=np.array([0.0, 0.5, 1.0]),
        lat=np.array([45.0, 45.001, 45.002]),
        lon=np.array([7.0, 7.0005, 7.001]),
        alt=np.array([100.0, 100.25, 0.1]),
        vel=np.tile([1.0, 2.0, -0.5], (n, 1)),
        euler_deg=np.tile([0.0, 1.0, 90.0], (n, 1)),
        gyro_bias=np.full((n, 3), 1e-4),
        accel_bias=np.full((n, 3), 0.01),
        hpl=np.array([3.0, 3.5, 4.0]),
        vpl=np.array([5.0, 5.5, 6.0]),
        gnss_used=np.array([True, False, True]),
        excluded_fixes=[{"t": 0.5, "test": "excluded", "nis": 40.0}],
        alerts=[{"t_start": 1.0, "t_end": 1.0, "limits": ["HAL"], "max_hpl": 4.0, "max_vpl": 6.0}],
    )


def test_track_csv_bytes(tmp_path) -> None:  # type: ignore[no-untyped-def]
    p = tmp_path / "TRACK.csv"
    track.write_track_csv(_track(), p)
    lines = p.read_text().splitlines()
    assert lines[0] == ",".join(track.TRACK_COLUMNS)
    assert lines[1] == "0,45,7,100,1,2,-0.5,0,1,90,0.0001,0.0001,0.0001,0.01,0.01,0.01,3,5,1"
    assert (
        lines[2] == "0.5,45.000999999999998,7.0004999999999997,100.25,1,2,-0.5,0,1,90,"
        "0.0001,0.0001,0.0001,0.01,0.01,0.01,3.5,5.5,0"
    )
    assert len(lines) == 4


def test_track_kml_bytes(tmp_path) -> None:  # type: ignore[no-untyped-def]
    p = tmp_path / "t.kml"
    track.write_track_kml(_track(), p, max_points=2)  # every 2nd row and the last
    assert p.read_text() == (
        '<?xml version="1.0" encoding="UTF-8"?>\n<kml xmlns="http://www.opengis.net/kml/2.2">'
        "<Document><name>uasnav INS track</name><Placemark><name>track</name>"
        "<LineString><altitudeMode>absolute</altitudeMode><coordinates>"
        "7.000000000,45.000000000,100.000 7.001000000,45.002000000,0.100"
        "</coordinates></LineString></Placemark></Document></kml>\n"
    )


def test_track_geojson(tmp_path) -> None:  # type: ignore[no-untyped-def]
    p = tmp_path / "t.geojson"
    track.write_track_geojson(_track(), p)
    gj = json.loads(p.read_text())
    line, fix, alert = gj["features"]
    assert line["geometry"]["coordinates"][1] == [7.0005, 45.001, 100.25]
    assert line["properties"] == {"name": "uasnav INS track", "t_start": 0.0, "t_end": 1.0}
    assert fix["geometry"]["coordinates"] == [7.0005, 45.001] and fix["properties"]["event"] == "excluded_fix"
    assert alert["geometry"]["coordinates"] == [7.001, 45.002] and alert["properties"]["limits"] == ["HAL"]


def test_plot_is_local_ned_about_the_first_point() -> None:
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    import pymap3d

    tr = _track()
    ax = track.plot_track(tr)
    e, n = (np.asarray(v, dtype=np.float64) for v in ax.lines[0].get_data())
    n_ref, e_ref, _ = pymap3d.geodetic2ned(tr.lat, tr.lon, tr.alt[0], tr.lat[0], tr.lon[0], tr.alt[0])
    np.testing.assert_allclose(n, n_ref, atol=1e-9)
    np.testing.assert_allclose(e, e_ref, atol=1e-9)
    # 0.002° of latitude at 45°: the WGS-84 meridian radius there, M = a(1−e²)/(1−e²sin²φ)^1.5
    # = 6 367 382 m, makes it 222.27 m (a 6 371 km sphere would give 222.39 m)
    assert n[2] == pytest.approx(222.27, abs=0.01)
