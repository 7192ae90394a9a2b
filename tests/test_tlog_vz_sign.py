"""GLOBAL_POSITION_INT.vz is positive down (MAVLink); logs of older ArduPilot firmware carry it
positive up, and the tlog readers turn both into a downward speed."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from uasnav.io import open_log
from uasnav.io.formats.tlog import read_tlog_flight, vz_down_sign
from uasnav.io.tlog_write import write_tlog_flight


def _climb_and_descend(n: int = 60) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(n, dtype=float)
    up = np.where(t < n / 2, 2.0, -1.5)  # m/s, up
    alt = 100.0 + np.concatenate([[0.0], np.cumsum(up[:-1])])
    return t, alt, up


def test_sign_follows_the_logs_own_altitude() -> None:
    t, alt, up = _climb_and_descend()
    assert vz_down_sign(t, alt, -up) == 1.0  # as MAVLink defines it
    assert vz_down_sign(t, alt, up) == -1.0  # positive up: turned around
    # hovering (no altitude change) or too short: the definition holds
    assert vz_down_sign(t, np.full_like(t, 50.0), np.zeros_like(t)) == 1.0
    assert vz_down_sign(t[:2], alt[:2], up[:2]) == 1.0


def test_written_log_keeps_positive_down(tmp_path: Path) -> None:
    t, alt, up = _climb_and_descend()
    vel = np.column_stack([np.full_like(t, 3.0), np.zeros_like(t), -up])
    path = tmp_path / "climb.tlog"
    write_tlog_flight(
        path,
        t_unix=1.7e9 + t,
        lat=47.0 + t * 1e-5,
        lon=np.full_like(t, 8.0),
        alt=alt,
        vel_ned=vel,
        waypoints={},
    )
    fl = read_tlog_flight(path)
    assert np.allclose(fl.vel_ned[:, 2], -up, atol=0.011)


def test_phoenix_telemetry_descends_with_positive_down_speed(shared_data: Path) -> None:
    log = open_log(shared_data / "flights" / "phoenix_mission1_arducopter.tlog", need=("flight", "nav"))
    for t, alt, vd in (
        (log.flight.t, log.flight.alt, log.flight.vel_ned[:, 2]),
        (log.nav.reference.t, log.nav.reference.alt, log.nav.reference.vel[:, 2]),
    ):
        dt = np.diff(t)
        ok = dt > 0
        climb = np.diff(alt)[ok] / dt[ok]
        v = 0.5 * (vd[1:] + vd[:-1])[ok]
        moving = np.abs(climb) > 0.5
        assert moving.sum() >= 20
        # altitude falling while the downward speed is positive, and the reverse
        assert np.mean(np.sign(v[moving]) == -np.sign(climb[moving])) > 0.8
