"""Sensor error models of the simulator, loaded from preset data files.

A preset (``presets/<name>.json``) lists every error term with its unit as text
(``"3.18 deg/√h"``); :func:`load_preset` converts them to SI with :mod:`uasnav.units`, so the
model in memory is SI only:

===================  ============================  ==========================================
term                 gyro / accel SI unit          meaning
===================  ============================  ==========================================
white                rad/√s / m/s/√s               ARW / VRW (white rate noise density N)
bias_instability     rad/s / m/s²                  B of the IEEE 952 flicker floor (σ_min = 0.664 B)
rate_random_walk     rad/s/√s / m/s²/√s            K (σ(τ) = K √(τ/3))
turn_on_bias         rad/s / m/s²                  1-σ of the run-to-run constant bias
quantization         rad/s / m/s²                  output LSB (0 → no rounding)
scale_factor         1                             1-σ of the per-axis scale-factor error
misalignment         rad                           1-σ of the off-diagonal (small-angle) terms
g_sensitivity        rad·s/m (gyro only)           1-σ of the g-sensitivity matrix entries
===================  ============================  ==========================================

The thermal block holds a per-axis bias–temperature curve

    b(T) = a₁ (T − T_ref) + Σ_i s_i tanh((T − c_i)/w_i) + Σ_j g_j exp(−((T − m_j)/v_j)²) − b₀

(smooth, non-polynomial: the tanh steps and Gaussian bumps create the local changes of trend
of thesis Figure 29; ``b₀`` makes b(T_ref) = 0), a hysteresis offset ``h`` between heating and
cooling branches, a thermal scale-factor coefficient and a temperature coefficient of the
white-noise level.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import DataFormatError, InputError
from uasnav.units import parse_quantity

FloatArray = NDArray[np.float64]
PRESET_NAMES = ("crs05-02", "ms8010", "ax1", "lsm6dsm")


@dataclass(frozen=True)
class ThermalErrorTruth:
    """The simulator's true temperature-dependent errors of one triad (SI; temperatures in °C).

    Ground truth that the simulated output is generated from (thermal bias curve with
    hysteresis, thermal scale-factor drift, temperature-dependent noise); not a calibration
    model fitted to data (those live in :mod:`uasnav.thermal`).

    Attributes
    ----------
    t_ref_c : float
        Reference temperature (°C) where the thermal bias is zero.
    linear : ndarray (3,)
        Linear coefficient a₁ per axis (SI unit per °C).
    steps : list of ndarray (k, 3)
        Per axis, rows ``(amplitude SI, centre °C, width °C)`` of tanh steps.
    bumps : list of ndarray (k, 3)
        Per axis, rows ``(amplitude SI, centre °C, width °C)`` of Gaussian bumps.
    hysteresis : float
        Offset between heating and cooling branches (SI): heating = b(T) + h/2,
        cooling = b(T) − h/2 once the branch is established.
    hysteresis_width_c : float
        Temperature travel (°C) over which the branch state relaxes by 1/e after a reversal.
    hysteresis_initial : float
        Branch state at t = 0 (+1 heating, −1 cooling).
    scale_factor_tc : float
        Scale-factor change per °C (1/°C).
    noise_tc : float
        Relative change of the white-noise density per °C (1/°C).
    """

    t_ref_c: float
    linear: FloatArray
    steps: list[FloatArray]
    bumps: list[FloatArray]
    hysteresis: float = 0.0
    hysteresis_width_c: float = 0.5
    hysteresis_initial: float = 1.0
    scale_factor_tc: float = 0.0
    noise_tc: float = 0.0

    def _raw(self, temp: FloatArray) -> FloatArray:
        t = temp
        out = np.empty((t.size, 3))
        for ax in range(3):
            y = self.linear[ax] * (t - self.t_ref_c)
            for a, c, w in self.steps[ax]:
                y = y + a * np.tanh((t - c) / w)
            for a, c, w in self.bumps[ax]:
                y = y + a * np.exp(-(((t - c) / w) ** 2))
            out[:, ax] = y
        return out

    def curve(self, temp_c: Any) -> FloatArray:
        """Branch-free bias curve b(T) (n, 3), zero at ``t_ref_c`` (SI)."""
        t = np.atleast_1d(np.asarray(temp_c, dtype=np.float64))
        return self._raw(t) - self._raw(np.array([self.t_ref_c]))

    def derivative(self, temp_c: Any) -> FloatArray:
        """∂b/∂T (n, 3) (SI per °C); identical on both hysteresis branches."""
        t = np.atleast_1d(np.asarray(temp_c, dtype=np.float64))
        out = np.empty((t.size, 3))
        for ax in range(3):
            d = np.full(t.shape, self.linear[ax])
            for a, c, w in self.steps[ax]:
                d = d + a / w / np.cosh((t - c) / w) ** 2
            for a, c, w in self.bumps[ax]:
                u = (t - c) / w
                d = d - 2.0 * a * u / w * np.exp(-(u**2))
            out[:, ax] = d
        return out

    def branch_bias(self, temp_c: Any, branch: str) -> FloatArray:
        """b(T) ± h/2 on the ``"heating"`` (+) or ``"cooling"`` (−) branch (n, 3)."""
        sign = _branch_sign(branch)
        return self.curve(temp_c) + sign * 0.5 * self.hysteresis

    def branch_state(self, temp_c: FloatArray) -> FloatArray:
        """Hysteresis branch state s ∈ [−1, 1] along a temperature history (n,).

        ``s`` relaxes towards +1 while heating and −1 while cooling, by ``1 − exp(−|ΔT|/w)``
        per step (a rate-independent, Preisach-like operator: it depends on the temperature
        path, not on time). Evaluated per monotone segment in closed form.
        """
        t = np.asarray(temp_c, dtype=np.float64)
        s = np.empty(t.size)
        state = float(self.hysteresis_initial)
        if t.size == 0:
            return s
        s[0] = state
        d = np.diff(t)
        direction = np.sign(d)
        # carry the last non-zero direction through flat parts (ΔT = 0 → no change anyway)
        nz = np.flatnonzero(direction)
        if nz.size == 0:
            s[:] = state
            return s
        bounds = np.flatnonzero(np.diff(direction[nz])) + 1
        seg_starts = np.concatenate([[0], nz[bounds]])
        seg_ends = np.concatenate([nz[bounds], [d.size]])
        travel = np.concatenate([[0.0], np.cumsum(np.abs(d))])
        w = max(self.hysteresis_width_c, 1e-12)
        for a, b in zip(seg_starts, seg_ends, strict=True):
            target = direction[nz[np.searchsorted(nz, a)]]
            dl = travel[a + 1 : b + 1] - travel[a]
            s[a + 1 : b + 1] = target + (state - target) * np.exp(-dl / w)
            state = float(s[b])
        return s

    def bias(self, temp_c: FloatArray) -> FloatArray:
        """Thermal bias (n, 3) along a die-temperature history, including hysteresis."""
        t = np.asarray(temp_c, dtype=np.float64)
        out = self.curve(t)
        if self.hysteresis != 0.0:
            out += 0.5 * self.hysteresis * self.branch_state(t)[:, None]
        return out

    def scaled(self, factors: FloatArray) -> ThermalErrorTruth:
        """A copy with each axis' bias curve multiplied by ``factors`` (3,); hysteresis unchanged."""
        f = np.asarray(factors, dtype=np.float64)
        steps = [s * np.array([f[i], 1.0, 1.0]) for i, s in enumerate(self.steps)]
        bumps = [b * np.array([f[i], 1.0, 1.0]) for i, b in enumerate(self.bumps)]
        return replace(self, linear=self.linear * f, steps=steps, bumps=bumps)


def _branch_sign(branch: str) -> float:
    if branch == "heating":
        return 1.0
    if branch == "cooling":
        return -1.0
    raise InputError(f"branch: expected 'heating' or 'cooling', got {branch!r}")


@dataclass(frozen=True)
class TriadModel:
    """Error model of one sensor triad (gyro or accelerometer), SI units (module table)."""

    kind: str
    white: float = 0.0
    bias_instability: float = 0.0
    bias_instability_tau_s: tuple[float, float] = (0.5, 2.0e4)
    rate_random_walk: float = 0.0
    turn_on_bias: float = 0.0
    quantization: float = 0.0
    scale_factor: float = 0.0
    misalignment: float = 0.0
    g_sensitivity: float = 0.0
    thermal: ThermalErrorTruth | None = None

    def without(self, *terms: str) -> TriadModel:
        """A copy with the named terms switched off (``"thermal"`` removes the thermal block)."""
        changes: dict[str, Any] = {}
        for term in terms:
            if term == "thermal":
                changes[term] = None
            elif term in _TERM_UNITS[self.kind]:
                changes[term] = 0.0
            else:
                raise InputError(f"unknown error term {term!r} for the {self.kind}")
        return replace(self, **changes)


@dataclass(frozen=True)
class TemperatureSensorModel:
    """Temperature channel and thermal behaviour of the package.

    Attributes
    ----------
    resolution_c : float
        Resolution of the reported die temperature (°C); 0 → no rounding.
    lag_s : float
        First-order time constant from chamber to die temperature (s).
    self_heating_c : float
        Steady die temperature rise over the chamber (°C) once powered.
    warmup_tau_s : float
        Time constant of the self-heating after power-on (s), used by the warm-up profile.
    ambient_c : float
        Default chamber temperature of the static profile (°C).
    noise_c : float
        1-σ white noise of the temperature reading before rounding (°C).
    """

    resolution_c: float = 0.01
    lag_s: float = 60.0
    self_heating_c: float = 0.0
    warmup_tau_s: float = 600.0
    ambient_c: float = 25.0
    noise_c: float = 0.0


@dataclass(frozen=True)
class SensorModel:
    """A complete IMU model: gyro and accelerometer triads, temperature channel, filter.

    Build with :func:`load_preset` and modify with :func:`dataclasses.replace` or
    :meth:`without`.
    """

    name: str
    gyro: TriadModel
    accel: TriadModel
    temperature: TemperatureSensorModel = field(default_factory=TemperatureSensorModel)
    antialias_hz: float | None = 30.0
    antialias_order: int = 2
    rate_hz: float = 100.0
    description: str = ""
    sources: tuple[str, ...] = ()

    def without(self, *terms: str) -> SensorModel:
        """Switch terms off in both triads, e.g. ``model.without("thermal", "turn_on_bias")``.

        ``"antialias"`` removes the output low-pass; ``"temp_quantization"`` the rounding of
        the temperature channel.
        """
        g, a, me = self.gyro, self.accel, self
        for term in terms:
            if term == "antialias":
                me = replace(me, antialias_hz=None)
            elif term == "temp_quantization":
                me = replace(me, temperature=replace(me.temperature, resolution_c=0.0))
            elif term == "g_sensitivity":
                g = g.without(term)
            else:
                g, a = g.without(term), a.without(term)
        return replace(me, gyro=g, accel=a)


_TERM_UNITS: dict[str, dict[str, str]] = {
    "gyro": {
        "white": "rad/√s",
        "bias_instability": "rad/s",
        "rate_random_walk": "rad/s/√s",
        "turn_on_bias": "rad/s",
        "quantization": "rad/s",
        "scale_factor": "1",
        "misalignment": "rad",
        "g_sensitivity": "rad/s/(m/s^2)",
    },
    "accel": {
        "white": "m/s/√s",
        "bias_instability": "m/s^2",
        "rate_random_walk": "m/s^2/√s",
        "turn_on_bias": "m/s^2",
        "quantization": "m/s^2",
        "scale_factor": "1",
        "misalignment": "rad",
    },
}


def preset_quantity(text: Any, si_unit: str, where: str) -> float:
    """A preset field: ``"3.18 deg/√h"`` → value in ``si_unit`` (dimension-checked by
    :func:`uasnav.units.parse_quantity`); plain numbers are taken as SI."""
    if isinstance(text, int | float) and not isinstance(text, bool):
        return float(text)
    try:
        return parse_quantity(text, si_unit)
    except InputError as e:
        raise DataFormatError(f"{where}: {e}") from None


def _thermal_from(d: dict[str, Any], kind: str, where: str) -> ThermalErrorTruth:
    unit = d["unit"]
    si = "rad/s" if kind == "gyro" else "m/s^2"
    k = preset_quantity(f"1 {unit}", si, f"{where}.unit")
    curve = d["curve"]
    if len(curve) != 3:
        raise DataFormatError(f"{where}.curve: expected 3 axes, got {len(curve)}")

    def rows(items: list[list[float]]) -> FloatArray:
        arr = np.asarray(items, dtype=np.float64).reshape(-1, 3)
        arr[:, 0] *= k
        if np.any(arr[:, 2] <= 0):
            raise DataFormatError(f"{where}: widths of steps/bumps must be > 0")
        return arr

    return ThermalErrorTruth(
        t_ref_c=float(d.get("t_ref_c", 25.0)),
        linear=np.array([float(c["linear"]) * k for c in curve]),
        steps=[rows(c.get("steps", [])) for c in curve],
        bumps=[rows(c.get("bumps", [])) for c in curve],
        hysteresis=preset_quantity(d.get("hysteresis", 0.0), si, f"{where}.hysteresis"),
        hysteresis_width_c=float(d.get("hysteresis_width_c", 0.5)),
        hysteresis_initial=float(d.get("hysteresis_initial", 1.0)),
        scale_factor_tc=preset_quantity(d.get("scale_factor_tc", 0.0), "1/K", f"{where}.scale_factor_tc"),
        noise_tc=preset_quantity(d.get("noise_tc", 0.0), "1/K", f"{where}.noise_tc"),
    )


def _triad_from(d: dict[str, Any], kind: str, where: str) -> TriadModel:
    units = _TERM_UNITS[kind]
    unknown = set(d) - set(units) - {"thermal", "bias_instability_tau_s"}
    if unknown:
        raise DataFormatError(f"{where}: unknown keys {sorted(unknown)}")
    vals = {k: preset_quantity(d.get(k, 0.0), u, f"{where}.{k}") for k, u in units.items()}
    for k, v in vals.items():
        if v < 0:
            raise DataFormatError(f"{where}.{k}: must be >= 0 (a 1-σ or density), got {v}")
    tau = tuple(float(x) for x in d.get("bias_instability_tau_s", (0.5, 2.0e4)))
    if len(tau) != 2 or not 0 < tau[0] < tau[1]:
        raise DataFormatError(f"{where}.bias_instability_tau_s: expected [lo, hi] with 0 < lo < hi")
    thermal = _thermal_from(d["thermal"], kind, f"{where}.thermal") if "thermal" in d else None
    return TriadModel(kind=kind, bias_instability_tau_s=(tau[0], tau[1]), thermal=thermal, **vals)


def model_from_dict(d: dict[str, Any], source: str = "<dict>") -> SensorModel:
    """Build a :class:`SensorModel` from the preset JSON structure (see ``presets/*.json``)."""
    try:
        temp = TemperatureSensorModel(**{k: float(v) for k, v in d.get("temperature", {}).items()})
        aa = d.get("antialias") or {}
        return SensorModel(
            name=str(d["name"]),
            gyro=_triad_from(d["gyro"], "gyro", f"{source}: gyro"),
            accel=_triad_from(d["accel"], "accel", f"{source}: accel"),
            temperature=temp,
            antialias_hz=float(aa["cutoff_hz"]) if aa.get("cutoff_hz") else None,
            antialias_order=int(aa.get("order", 2)),
            rate_hz=float(d.get("rate_hz", 100.0)),
            description=str(d.get("description", "")),
            sources=tuple(d.get("sources", ())),
        )
    except KeyError as e:
        raise DataFormatError(f"{source}: missing key {e.args[0]!r}") from None
    except TypeError as e:
        raise DataFormatError(f"{source}: {e}") from None


#: Largest preset file read (bytes); the shipped ones are about 2 KiB.
MAX_PRESET_BYTES = 1 << 20


def load_preset(name: str) -> SensorModel:
    """Load a preset by name (``crs05-02``, ``ms8010``, ``ax1``, ``lsm6dsm``) or JSON path."""
    if isinstance(name, SensorModel):
        return name
    if name.endswith(".json"):
        from pathlib import Path

        from uasnav import jsoncheck

        p = Path(name)
        if not p.exists():
            raise DataFormatError("no such preset file", path=str(p))
        with jsoncheck.reraise_in(str(p)):
            d = jsoncheck.parse(jsoncheck.read_text(p, MAX_PRESET_BYTES), "not a preset: not valid JSON")
            if not isinstance(d, dict):
                raise DataFormatError(f"not a preset: expected a JSON object, got {type(d).__name__}")
        return model_from_dict(d, str(p))
    if name not in PRESET_NAMES:
        raise InputError(f"unknown preset {name!r}; available: {', '.join(PRESET_NAMES)}")
    text = resources.files("uasnav.sim").joinpath("presets", f"{name}.json").read_text(encoding="utf-8")
    return model_from_dict(json.loads(text), f"preset {name}")


__all__ = [
    "PRESET_NAMES",
    "SensorModel",
    "TemperatureSensorModel",
    "ThermalErrorTruth",
    "TriadModel",
    "load_preset",
    "model_from_dict",
    "preset_quantity",
]
