"""Writes ``src/inputs.rs``: the fixed inputs of the firmware tests, from the uasnav simulator.

Run with an environment where ``uasnav`` (with its extension) imports::

    python crates/nav-firmware/gen_inputs.py

Every number is written with ``repr`` (shortest round-trip form), so the Rust literal parses
to the same f64 bits; the firmware and the host reference read the same constants.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from uasnav.sim import simulate, simulate_array
from uasnav.sim.flight import simulate_flight
from uasnav.thermal.neural import nguyen_widrow, unpack, Network

OUT = Path(__file__).with_name("src") / "inputs.rs"
N_IMU = 300  # samples per case at 100 Hz


def arr(name: str, a: np.ndarray, doc: str) -> str:
    a = np.asarray(a, dtype=np.float64)
    if a.ndim == 1:
        body = ", ".join(repr(float(x)) for x in a)
        return f"/// {doc}\npub static {name}: [f64; {a.size}] = [{body}];\n"
    rows = ",\n    ".join("[" + ", ".join(repr(float(x)) for x in r) + "]" for r in a)
    return f"/// {doc}\npub static {name}: [[f64; {a.shape[1]}]; {a.shape[0]}] = [\n    {rows},\n];\n"


def main() -> None:
    parts = [
        "//! Fixed inputs of the firmware tests, written by `gen_inputs.py` from the uasnav\n"
        "//! simulator (do not edit by hand). Units: SI, body frame for IMU samples, NED for\n"
        "//! velocities, radians for latitude/longitude, ellipsoidal height in metres.\n"
        "#![allow(clippy::approx_constant, clippy::excessive_precision, clippy::unreadable_literal)]\n"
    ]
    # Flight (GNSS/INS, attitude): 1 s on the ground, then take-off and the circuit.
    f = simulate_flight(duration_s=30.0, static_s=5.0, seed=3)
    i0 = 400
    imu = f.imu
    sl = slice(i0, i0 + N_IMU)
    parts.append(arr("FLIGHT_GYRO", imu.gyro[sl], "Flight gyro (rad/s, body)."))
    parts.append(arr("FLIGHT_ACCEL", imu.accel[sl], "Flight specific force (m/s², body)."))
    tr = f.truth
    k = int(np.argmin(np.abs(tr.t - imu.t[i0])))
    e = np.radians(tr.euler_deg[k])
    parts.append(arr("FLIGHT_EULER0", e, "Initial roll, pitch, yaw (rad, 3-2-1, body → NED)."))
    llh0 = [math.radians(tr.lat[k]), math.radians(tr.lon[k]), tr.alt[k]]
    parts.append(arr("FLIGHT_LLH0", llh0, "Initial latitude, longitude (rad), ellipsoidal height (m)."))
    parts.append(arr("FLIGHT_VEL0", tr.vel[k], "Initial velocity (m/s, NED)."))
    g = f.gnss
    t_end = imu.t[i0 + N_IMU - 1]
    sel = (g.t > imu.t[i0]) & (g.t <= t_end)
    # Each fix is applied after the IMU sample with the same time stamp.
    idx = np.round((g.t[sel] - imu.t[i0]) / 0.01).astype(int)
    fixes = np.column_stack(
        [idx, np.radians(g.lat[sel]), np.radians(g.lon[sel]), g.alt[sel], g.vel[sel], g.h_acc[sel], g.v_acc[sel], g.s_acc[sel]]
    )
    parts.append(
        arr(
            "GNSS_FIXES",
            fixes,
            "GNSS fixes: IMU sample index after which it applies, latitude, longitude (rad), "
            "ellipsoidal height (m), velocity N, E, D (m/s), σ horizontal (m), σ vertical (m), σ speed (m/s).",
        )
    )
    # Static lab log on a warming die (ZUPT, TCZUPT, static detector).
    s = simulate("crs05-02", profile="ramp", duration=N_IMU / 100.0, rate=100.0, seed=2, euler_rad=(0.02, -0.01, 0.5))
    parts.append(arr("STATIC_GYRO", s.gyro, "Static gyro (rad/s, body)."))
    parts.append(arr("STATIC_ACCEL", s.accel, "Static specific force (m/s², body)."))
    parts.append(arr("STATIC_TEMP", s.temp, "Die temperature (°C)."))
    # Thermal MLP (1-6-6-1, tanh): Nguyen–Widrow weights, output scaled to a gyro bias.
    rng = np.random.default_rng(7)
    like = Network(np.zeros(6), np.zeros(6), np.zeros((6, 6)), np.zeros(6), np.zeros(6), 0.0, 30.0, 1 / 40.0, 1e-3, 2e-3)
    net = unpack(nguyen_widrow(6, 6, rng), 6, 6, like)
    parts.append(arr("MLP_W1", net.W1, "Hidden layer 1 weights (6×1)."))
    parts.append(arr("MLP_B1", net.b1, "Hidden layer 1 biases."))
    parts.append(arr("MLP_W2", net.W2.ravel(), "Hidden layer 2 weights (6×6, row-major)."))
    parts.append(arr("MLP_B2", net.b2, "Hidden layer 2 biases."))
    parts.append(arr("MLP_W3", net.w3, "Output weights (1×6)."))
    parts.append(
        arr(
            "MLP_NORM",
            [float(net.b3), net.in_offset, net.in_gain, net.out_offset, net.out_scale],
            "Output bias, input offset (°C), input gain (1/°C), output offset (rad/s), output scale (rad/s).",
        )
    )
    # Redundant cube array: six triaxial gyros, one per face.
    a = simulate_array("lsm6dsm", shape="cube", duration=N_IMU / 100.0, rate=100.0, seed=1)
    z = np.concatenate([x.gyro for x in a], axis=1)
    parts.append(arr("ARRAY_MOUNTINGS", np.concatenate([np.asarray(x.meta["mounting"]) for x in a]), "Six mountings C_b^s stacked (18×3)."))
    parts.append(arr("ARRAY_GYRO", z, "Six gyro triads in their sensor frames (rad/s), 18 axes per sample."))
    OUT.write_text("\n".join(parts))


if __name__ == "__main__":
    main()
