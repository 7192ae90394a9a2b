"""Every published number of the thesis that uasnav compares with, once, with its source.

Chapter 4 and 5 of the thesis (``../shared/reference/thesis-ch4-ch5.md``): each constant names
its table or figure (and equation where one defines it) and its unit. Experiments and the report
import them from here; nothing else restates a thesis number.
"""

from __future__ import annotations

# --- allan / simulator (§4.2.2–4.2.4) ------------------------------------------------------------

#: Table 3 (CRS05-02 gyro, ZUPT filter): σ_ARW (deg/√h) and σ_GBI (deg/s).
TABLE3 = {"arw_deg_sqrt_h": 3.18, "gbi_deg_s": 1.5e-4}
#: Table 4 (MS8010 accelerometer, ZUPT filter): σ_VRW (m/s/√h) and σ_ABI (m/s/h).
TABLE4 = {"vrw_m_s_sqrt_h": 0.05, "abi_m_s_h": 2.0}
#: §4.2.4, Figure 29 (°C): die temperature of the soak test, (first, last) step.
FIG29_SOAK_RANGE_C = (-20.53, 37.30)
#: §4.2.4, Figure 29 (°C): temperature step of the soak test.
FIG29_SOAK_STEP_C = 5.0
#: §4.2.4, Figure 30 (°C): die temperature range of the ramp test, (low, high).
FIG30_RAMP_RANGE_C = (27.28, 34.08)
#: §4.2.4, Figure 30 (°C/min): ramp rate of the ramp test.
FIG30_RAMP_RATE_C_PER_MIN = 2.0

# --- attitude (§4.2.5.3) ------------------------------------------------------------------------

#: Table 7 (Δω_MAX residual): threshold θ (rad) → (t_NN (s), t_PF (s), Δt% (%, eq. 36, as printed)).
TABLE7: dict[float, tuple[float, float, float]] = {
    1.70e-3: (2.9, 2.4, 21.8),
    3.50e-3: (5.9, 4.6, 25.80),
    8.70e-3: (14.5, 11.5, 26.10),
    1.75e-2: (29.4, 23.0, 27.38),
}
#: Table 8 (Δω_RMS residual): threshold θ (rad) → (t_NN (s), t_PF (s), Δt% (%, eq. 36, as printed)).
TABLE8: dict[float, tuple[float, float, float]] = {
    1.70e-3: (3.3, 2.7, 19.27),
    3.50e-3: (6.7, 5.4, 22.02),
    8.70e-3: (17.2, 13.8, 25.00),
    1.75e-2: (34.9, 28.2, 23.76),
}

# --- calibration (§4.2.5) -------------------------------------------------------------------------

#: Figure 34 / eq. (34): extremes of Δω(T) = ‖ω_NN − ω_PF‖ over the ramp range: "max" and "rms"
#: (rad/s), "t_max" and "t_rms" the temperatures where they occur (°C).
FIG34_DELTA_OMEGA = {"max": 1.83e-4, "t_max": 27.78, "rms": 1.07e-4, "t_rms": 32.60}

# --- zupt (§4.2.6) --------------------------------------------------------------------------------

#: Table 9 (rad/s): mean residual of the 30 s moving-average reference per axis, (calibrated, raw).
TABLE9 = {"x": (1.68e-6, 9.53e-6), "y": (2.98e-6, 6.80e-6), "z": (3.43e-6, 1.03e-5)}
#: Table 10 (rad/s): RMS bias error per axis, (ZUPT, TCZUPT), nominal and residual 15 deg/h.
TABLE10 = {
    "nominal": {"x": (4.15e-5, 5.33e-5), "y": (7.48e-5, 2.97e-5), "z": (6.07e-5, 3.30e-5)},
    "residual": {"x": (3.98e-5, 4.13e-5), "y": (9.72e-5, 3.88e-5), "z": (8.17e-5, 3.01e-5)},
}
#: Table 11 (s): convergence time to 1e-5 rad/s per axis, residual 15 deg/h, (ZUPT, TCZUPT).
TABLE11 = {"x": (140, 65), "y": (345, 127), "z": (85, 53)}
#: Table 12 (rad/s): (mean, std) of the RMS bias error over 5 × 5 min segments, nominal, per filter
#: and axis.
TABLE12 = {
    "zupt": {"x": (3.42e-5, 0.77e-5), "y": (3.58e-5, 0.89e-5), "z": (4.36e-5, 0.82e-5)},
    "tczupt": {"x": (4.70e-5, 0.61e-5), "y": (2.63e-5, 0.65e-5), "z": (3.89e-5, 0.70e-5)},
}
#: Table 13 (rad/s): as Table 12, residual 15 deg/h.
TABLE13 = {
    "zupt": {"x": (6.49e-5, 0.92e-5), "y": (8.88e-5, 0.92e-5), "z": (7.16e-5, 0.79e-5)},
    "tczupt": {"x": (3.81e-5, 0.54e-5), "y": (4.58e-5, 0.84e-5), "z": (3.36e-5, 0.35e-5)},
}

# --- redundancy (§4.3) ----------------------------------------------------------------------------

#: Table 14 (k_r dimensionless, eq. 40): rows (config no., gyros per face, total number of
#: single-axis gyros along the cube's face normals, k_r per IMU axis).
TABLE14: tuple[tuple[int, float, int, float], ...] = (
    (1, 0.5, 3, 1.0),
    (2, 1.0, 6, 0.71),
    (3, 1.5, 9, 0.58),
    (4, 2.0, 12, 0.50),
    (5, 3.0, 18, 0.41),
)
#: Table 15: attitude threshold θ (rad) → (t_red of the fused cube (s), t of one sensor (s),
#: Δt % of eq. 46).
TABLE15: dict[float, tuple[float, float, float]] = {
    1.70e-3: (1.80, 1.43, 25.87),
    3.50e-3: (2.50, 2.00, 21.95),
    8.70e-3: (4.00, 2.80, 44.96),
    1.75e-2: (7.00, 3.75, 87.73),
}

# --- trajectory (§5.1) ----------------------------------------------------------------------------

#: §5.1.4.2 (Figures 59–62): the four training corner elements, (θ (deg), θ_w (deg), ΔV (m/s)
#: relative to the element's initial speed).
SEC5142_TRAINING_ELEMENTS: tuple[tuple[float, float, float], ...] = (
    (72.0, 64.0, 0.25),
    (105.0, 140.0, 0.35),
    (80.0, 90.0, 0.35),
    (130.0, 170.0, 0.40),
)
#: Table 17: per test piece, (t_NN (s), ((t_Real (s), e% (%, eq. 59)) of each of the three test flights)).
TABLE17: tuple[tuple[float, tuple[tuple[float, float], ...]], ...] = (
    (27.27, ((26.15, 4.28), (26.28, 3.77), (28.18, 3.23))),
    (25.13, ((25.67, 2.10), (24.50, 2.57), (26.00, 3.35))),
)

# --- mission (§5.2) -------------------------------------------------------------------------------

#: Table 22 (precision agriculture): requirement → value as printed, with its unit.
TABLE22: dict[str, str] = {
    "range": "1500 m",
    "resolution": "0.05 m",
    "image size": "70 x 70 m",
    "altitude": "50 m",
    "imagery": "multispectral",
    "wind": "5 m/s",
    "rain": "no",
    "order by": "cost",
    "regulations": "Italy (ENAC, 2016)",
}
#: Table 23 (precision agriculture): scoring parameter → target and limit as printed, with units.
TABLE23: dict[str, str] = {
    "range": "min 1500 m, target 5000 m",
    "weight": "target 800 g, max 1600 g",
    "cost": "target 4000 $, max 7000 $",
    "angular resolution": "target 0.01°, max 0.06°",
}
#: Table 24 (precision agriculture): the five best configurations, (UAS, camera, Score_Total
#: (dimensionless, eq. 61, lower is better)).
TABLE24: tuple[tuple[str, str, float], ...] = (
    ("Phantom 4", "Micro ADC", 1.18),
    ("Hexacopter Hawk", "Micro ADC", 1.34),
    ("Phantom 4", "Snap ADC", 1.56),
    ("Based 1", "Micro ADC", 1.64),
    ("Phantom 3", "Micro ADC", 1.65),
)
