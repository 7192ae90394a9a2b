"""The GNSS/INS configuration crosses into Rust as one typed object (``FilterConfig``), and
the classic filter mode has one name ("classic"; "zupt" accepted)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from uasnav import _core, ins, zupt
from uasnav.errors import InputError
from uasnav.ins.core import FilterConfig
from uasnav.sim.flight import simulate_flight


@pytest.fixture(scope="module")
def flight() -> ins.Flight:
    return simulate_flight(duration_s=30.0, seed=3)


def _run_core(flight: ins.Flight, config: object) -> dict[str, Any]:
    """`_core.ins_run` on the first 10 s of ``flight`` with ``config`` as given."""
    imu, g = flight.imu, flight.gnss
    k = int(np.searchsorted(imu.t, 10.0))
    c = np.ascontiguousarray
    llh = c(np.column_stack([np.radians(g.lat), np.radians(g.lon), g.alt]))
    acc = c(np.column_stack([g.h_acc, g.v_acc, g.s_acc]))
    return _core.ins_run(
        c(imu.t[:k]),
        c(imu.gyro[:k]),
        c(imu.accel[:k]),
        c(g.t),
        llh,
        c(g.vel),
        acc,
        config=config,  # type: ignore[arg-type]
    )


def test_every_field_is_read_by_rust_and_a_wrong_type_names_it(flight: ins.Flight) -> None:
    """Each FilterConfig field reaches Rust: a str in it is an InputError naming the field (a
    field Rust did not read would pass silently)."""
    names = [f.name for f in dataclasses.fields(FilterConfig)]
    assert len(names) == 33 and FilterConfig.FLOAT_FIELDS <= set(names)
    for name in names:
        change: dict[str, Any] = {name: 1.5 if name in ("mode", "discretisation") else "1.5"}
        bad = dataclasses.replace(FilterConfig(), **change)
        with pytest.raises(InputError, match=rf"config: .*FilterConfig\.{name}\b"):
            _run_core(flight, bad)


def test_values_are_checked_by_nav_core_and_none_keeps_its_default(flight: ins.Flight) -> None:
    out = _run_core(flight, FilterConfig())  # every field None: nav-core's defaults
    assert np.isfinite(out["llh"]).all()
    with pytest.raises(InputError, match="baro_std_m"):
        _run_core(flight, FilterConfig(baro_std_m=-1.0))
    with pytest.raises(InputError, match="window_fixes"):
        _run_core(flight, FilterConfig(window_fixes=-1))
    with pytest.raises(InputError, match="lever_arm_m"):
        _run_core(flight, FilterConfig(lever_arm_m=(0.0, 1.0)))  # type: ignore[arg-type]
    with pytest.raises(InputError, match="mode"):
        _run_core(flight, FilterConfig(mode="fancy"))  # type: ignore[arg-type]
    with pytest.raises(InputError, match="discretisation"):
        _run_core(flight, FilterConfig(discretisation="third"))  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"config: .*has no attribute 'mode'"):
        _run_core(flight, object())


def test_a_setting_changes_the_run(flight: ins.Flight) -> None:
    """A field that crosses is applied (not only type-checked): the lever arm moves the track."""
    a = _run_core(flight, FilterConfig())
    b = _run_core(flight, FilterConfig(lever_arm_m=(0.0, 0.0, -5.0)))
    assert not np.array_equal(a["llh"], b["llh"])


def test_extra_sets_float_fields_only(flight: ins.Flight) -> None:
    cfg = ins.InsConfig(extra={"baro_std_m": 2.0, "zupt_interval_s": 1})
    fc = cfg.filter_config(declination_rad=0.1)
    assert fc.baro_std_m == 2.0 and fc.zupt_interval_s == 1.0 and fc.declination_rad == 0.1
    assert fc.window_fixes == cfg.window_fixes and fc.lever_arm_m == cfg.lever_arm_m
    with pytest.raises(InputError, match="unknown key 'window_fixes'"):
        ins.InsConfig(extra={"window_fixes": 3}).filter_config(0.0)
    with pytest.raises(InputError, match=r"extra\['baro_std_m'\]: expected a float"):
        ins.run(flight, ins.InsConfig(extra={"baro_std_m": "two"}))  # type: ignore[dict-item]


def test_zupt_is_another_name_of_the_classic_mode(flight: ins.Flight) -> None:
    a = ins.run(flight, ins.InsConfig(decimation=50))
    b = ins.run(flight, ins.InsConfig(mode="zupt", decimation=50))  # type: ignore[arg-type]
    assert a.summary["mode"] == b.summary["mode"] == "classic"
    assert np.array_equal(a.lat, b.lat) and np.array_equal(a.gyro_bias, b.gyro_bias)

    log = flight.imu.between(0.0, 20.0)
    cfg = zupt.ZuptConfig(levelling_s=2.0, decimation=100, heading_rad=0.0)
    z = zupt.run(log, "zupt", config=cfg)
    c = zupt.run(log, "classic", config=cfg)
    d = zupt.run(log, config=cfg)
    assert z.mode == c.mode == d.mode == "classic"
    assert np.array_equal(z.gyro_bias, c.gyro_bias) and np.array_equal(z.gyro_bias, d.gyro_bias)
