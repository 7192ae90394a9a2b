"""Autopilot navigation limits from flight-log parameters, and the kinematic model that uses them."""

from __future__ import annotations

import numpy as np
import pytest

from uasnav.errors import DataFormatError, InputError
from uasnav.io.autopilot_limits import DEFAULT_LIMITS, AutopilotLimits, read_autopilot_limits
from uasnav.trajectory.baselines import kinematic_residual_factor, kinematic_times

TLOG = "flights/phoenix_mission1_arducopter.tlog"
BIN = "logs/ardupilot_log171.bin"


def _pymavlink_params(path, kind):
    """The parameters as pymavlink reads them directly (the reference)."""
    from pymavlink import mavutil

    conn = mavutil.mavlink_connection(str(path))
    out = {}
    while (m := conn.recv_match(type=[kind])) is not None:
        if kind == "PARAM_VALUE":
            out[m.param_id.rstrip("\x00")] = float(m.param_value)
        else:
            out[m.Name.rstrip("\x00")] = float(m.Value)
    return out


@pytest.mark.parametrize(("rel", "kind"), [(TLOG, "PARAM_VALUE"), (BIN, "PARM")])
def test_ardupilot_limits_are_the_logged_parameters_in_si(shared_data, rel, kind):
    ref = _pymavlink_params(shared_data / rel, kind)
    lim = read_autopilot_limits(shared_data / rel)
    assert lim.cruise_ms == pytest.approx(ref["WPNAV_SPEED"] / 100)
    assert lim.accel_ms2 == pytest.approx(ref["WPNAV_ACCEL"] / 100)
    assert lim.climb_ms == pytest.approx(ref["WPNAV_SPEED_UP"] / 100)
    assert lim.descent_ms == pytest.approx(ref["WPNAV_SPEED_DN"] / 100)
    assert lim.accel_z_ms2 == pytest.approx(ref["WPNAV_ACCEL_Z"] / 100)
    assert set(lim.source) == {"cruise_ms", "accel_ms2", "climb_ms", "descent_ms", "accel_z_ms2"}


def test_px4_limits_from_ulog_header(shared_data):
    from pyulog import ULog

    for name in ("px4_sample.ulg", "px4_sample_log_small.ulg"):
        p = shared_data / "logs" / name
        ref = ULog(str(p), []).initial_parameters
        lim = read_autopilot_limits(p)
        assert lim.cruise_ms == pytest.approx(ref["MPC_XY_CRUISE"])
        # MPC_ACC_HOR when logged, else MPC_ACC_HOR_MAX
        assert lim.accel_ms2 == pytest.approx(ref.get("MPC_ACC_HOR", ref["MPC_ACC_HOR_MAX"]))
        assert lim.climb_ms == pytest.approx(ref["MPC_Z_VEL_MAX_UP"])
        assert lim.descent_ms == pytest.approx(ref["MPC_Z_VEL_MAX_DN"])
    # the small log carries both: MPC_ACC_HOR (3 m/s²) wins over MPC_ACC_HOR_MAX (2 m/s²)
    small = read_autopilot_limits(shared_data / "logs" / "px4_sample_log_small.ulg")
    assert small.accel_ms2 == 3.0
    # vertical: MPC_ACC_UP_MAX (4 m/s²) wins over MPC_ACC_DOWN_MAX (3 m/s²); the other log has neither
    assert small.accel_z_ms2 == 4.0
    assert read_autopilot_limits(shared_data / "logs" / "px4_sample.ulg").accel_z_ms2 is None


def test_bad_files_are_refused(tmp_path):
    with pytest.raises(DataFormatError, match="no autopilot parameters"):
        read_autopilot_limits(tmp_path / "flight.csv")
    with pytest.raises(DataFormatError, match="no such file"):
        read_autopilot_limits(tmp_path / "missing.tlog")
    (tmp_path / "junk.ulg").write_bytes(b"not a ulog at all")
    with pytest.raises(DataFormatError):
        read_autopilot_limits(tmp_path / "junk.ulg")


def test_defaults_fill_only_the_unknown_limits():
    lim = AutopilotLimits(accel_ms2=2.0, source=("accel_ms2",)).or_defaults()
    assert lim.accel_ms2 == 2.0 and lim.source == ("accel_ms2",)
    assert (lim.cruise_ms, lim.climb_ms, lim.descent_ms) == (
        DEFAULT_LIMITS.cruise_ms,
        DEFAULT_LIMITS.climb_ms,
        DEFAULT_LIMITS.descent_ms,
    )


@pytest.mark.parametrize("accel", [0.5, 1.0, 5.0])
def test_kinematic_time_of_a_straight_leg_closed_form(accel):
    # from rest to rest over L ≥ V²/a: two ramps of V/a s each, t = L/V + V/a
    v, length = 5.0, 200.0
    plan = np.array([[0.0, 0.0], [0.0, length]])
    t = kinematic_times(plan, np.array([0.0]), np.array([length]), v, accel_ms2=accel)
    assert t[0] == pytest.approx(length / v + v / accel, rel=1e-6)


def test_residual_factor_by_hand():
    assert kinematic_residual_factor(np.array([10.0, 30.0]), np.array([10.0, 10.0])) == 2.0
    # non-positive or non-finite times are left out; none left: no correction
    assert kinematic_residual_factor(np.array([10.0, np.nan]), np.array([5.0, 1.0])) == 2.0
    assert kinematic_residual_factor(np.array([1.0]), np.array([0.0])) == 1.0


def test_leave_one_run_out_refuses_a_bad_acceleration(shared_data):
    from uasnav.trajectory.flights import flight_samples, leave_one_run_out

    fs = flight_samples([shared_data / TLOG])
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(InputError, match="acceleration limit"):
            leave_one_run_out(fs, accel_ms2=bad)
