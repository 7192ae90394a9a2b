"""Runs the nav-core firmware on QEMU's Cortex-M4F and Cortex-M7 and checks it against the host.

Usage (``make embedded`` calls it)::

    python3 check.py HOST_BIN M4_ELF M7_ELF [--size TOOL] [--objdump TOOL]

1. The host reference (HOST_BIN: the same cases, nav-core without ``std``, libm maths) and the
   firmware on ``mps2-an386`` (Cortex-M4F, f64 in software) and ``mps2-an500`` (Cortex-M7,
   double-precision FPU) print every output value as f64 bits.
2. **Bit-identical**: each firmware output equals the host output of the same precision (the
   same IEEE-754 operations in the same order, libm on both sides).
3. **f32 against f64**: every f32 output lies within the bound derived below of the f64 output
   (the f64 rounding error, ~1e-16 relative, is neglected next to f32's).
4. Prints the budget table: instructions per call (SysTick under ``-icount shift=0``,
   calibrated on a loop of known length), cycle ranges from the CPI ranges, stack high-water
   marks, the highest IMU rate within 25 % of a 168 MHz STM32F4 / 480 MHz STM32H7; the flash
   per algorithm and the remaining panic call sites.

Exit status 1 on any mismatch, bound violation, firmware error or QEMU failure.

Error bounds (u = 2⁻²⁴, the f32 unit roundoff; k = samples processed; m = updates applied)
--------------------------------------------------------------------------------------------
Each bound is a first-order forward-error bound: every f32 operation contributes at most
u·|operand scale| (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., §3.1:
a length-n dot product is within γ_n ≈ n·u of Σ|terms|), libm's f32 functions are within 2 ulp,
and local errors of successive samples add up linearly — the worst case, no cancellation
between samples, and no growth by the dynamics beyond the couplings named below (over the 3 s
of the cases the strapdown transition is the identity plus O(|F|·t) < 1 %, and a Kalman
update's closed loop I − KH is non-expansive). Counts are per sample, read off the code:

* attitude (quaternion components): a Hamilton product component is a 4-term dot product of
  unit quaternions, within 4u (Cauchy–Schwarz: Σ|terms| ≤ |q||p| = 1), 8u as a 4-vector; the
  rotation-vector exponential 3u; renormalisation (4 squares, 3 sums, sqrt, 4 divisions) 6u;
  rounding of rate, dt and their product, coning term 3u; libm sin/cos 2 ulp each: C = 30 per
  step (the angle error is twice the vector error, each component at most the vector). The
  initial quaternion from f32 Euler angles (3 rounded angles, 3 sin/cos pairs, 12-term
  products): C0 = 20. Bound: (C0 + k·C)·u.
* MLP: running forward-error bound through the network with the actual weights and
  activations (absolute values; γ_{n+2} per layer for the n-term sum, the bias and the f32
  rounding of each weight; tanh 1-Lipschitz with a 2-ulp libm result; derivative
  propagated the same way): see ``mlp_bounds``.
* ZUPT / TCZUPT / INS states (position, velocity, attitude, biases, per group g):
  u·S_g·(C_pred·k + C_upd·m), S_g the largest magnitude of the group over the reference run,
  floored at its initial σ (corrections are of the order of σ). C_pred = 60 (attitude step
  30 as above, DCM 15, f_n 9, velocity and position 6). C_upd = 2·n·κ(S): an n-row
  measurement's Cholesky solve is backward stable with a forward error ≤ c·n·u·κ(S)
  (Higham Thm 10.4); κ(S) ≤ (tr(HPHᵀ) + max R)/min R from the reference's own covariance
  diagonal and R (``kappa_*``). Velocity adds the attitude coupling δv̇ = f×ψ: g·t·(attitude
  bound); position the integral of the velocity bound over t. INS latitude/longitude/height
  are f64 in both builds; their difference comes from the f32 velocity and corrections: the
  position bound in metres, divided by the Earth radius for the angles.
* Covariance diagonal (per group): u·P_g·(C_P·k + C_upd·m), P_g the group's largest
  variance over the run, C_P = 32 (Φ P Φᵀ: two 15-term dot products and the Q term).
* Static detector statistic: the detector keeps running sums (add the new, subtract the oldest
  sample), so their error grows with every push: u·(2k + C)·T_max, T_max =
  (g + |a − g|max)²/σ_a² + |ω|max²/σ_ω² the largest per-sample term, C = 20 for the
  normalisation and the statistic. The decision must match unless the statistic lies
  within its bound of the threshold γ.
* FDI: the fused rate is a weighted least-squares solution over 18 axes with a well
  conditioned information matrix (a cube: HᵀWH = 6/σ²·I, κ = 1): |Δω| ≤ (2·18 + 30)·u·|z|max.
  The parity statistic Σr²/σ²: |Δχ²| ≤ 2·√(18·χ²)·δr/σ + 18u·χ², δr = (2·18 + 30)·u·|z|max.
  Validity, alarm and health flags must match exactly.
"""

from __future__ import annotations

import argparse
import math
import re
import struct
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

U = 2.0**-24
G = 9.81
DT = 0.01
EARTH_R = 6.35e6  # smallest WGS-84 radius of curvature (m): the angle bound's divisor
HERE = Path(__file__).resolve().parent

# Core clock (Hz) of the boards of the budget table, and the CPI range assumed per core.
# Cortex-M4F: single-cycle integer and f32 arithmetic, 2-cycle loads, 14-cycle VDIV/VSQRT,
# 1 + (1…3) cycles for a taken branch (Arm Cortex-M4 TRM, instruction timing table; the same
# table is reproduced in TI SWCU192 §3.3); flash wait states hidden by the STM32F4 ART
# accelerator on straight-line code: CPI 1.0 … 1.6.
# Cortex-M7: dual issue (CPI down to 0.5), FP latency 3, f64 multiplies occupying the FP pipe
# twice, 16…30-cycle divisions (LLVM's ARMScheduleM7.td), with the code in ITCM or I-cache:
# CPI 0.6 … 1.2.
BOARDS = {
    "m4": ("STM32F4 168 MHz (M4F)", 168e6, (1.0, 1.6)),
    "m7": ("STM32H7 480 MHz (M7)", 480e6, (0.6, 1.2)),
}
BUDGET = 0.25

RECORD = {"position": 9, "attitude": 5, "zupt": 33, "mlp": 3, "tczupt": 33, "ins": 33, "detector": 3, "fdi": 13}


def parse(text: str) -> tuple[dict, dict, dict]:
    """Values per precision and case, timing and stack per precision and step, calibration."""
    values: dict = defaultdict(dict)
    timing: dict = defaultdict(dict)
    cal: dict = {}
    prec = case = None
    for line in text.splitlines():
        w = line.split()
        if not w:
            continue
        if w[0] == "precision":
            prec = w[1]
        elif w[0] == "case":
            case = w[1]
            values[prec][case] = []
        elif w[0] == "v":
            values[prec][case].append(struct.unpack(">d", bytes.fromhex(w[1]))[0])
        elif w[0] == "t":
            timing[prec][w[1]] = {k: int(v) for k, v in (kv.split("=") for kv in w[2:])}
        elif w[0] == "cal":
            cal = {k: int(v) for k, v in (kv.split("=") for kv in w[1:])}
    return values, timing, cal


def records(case: str, v: list[float]) -> list[list[float]]:
    n = RECORD[case]
    return [v[i : i + n] for i in range(0, len(v), n)]


def inputs() -> dict[str, list]:
    """The arrays of ``src/inputs.rs`` (flattened)."""
    text = (HERE / "src" / "inputs.rs").read_text()
    out = {}
    for m in re.finditer(r"pub static (\w+): [^=]+= \[(.*?)\];", text, re.S):
        out[m.group(1)] = [float(x) for x in re.findall(r"[-+0-9.eE]+(?:e[-+]?\d+)?", m.group(2))]
    return out


def mlp_bounds(inp: dict, temps: list[float]) -> list[tuple[float, float]]:
    """Forward-error bounds (value, derivative) of the f32 MLP at each temperature."""
    w1, b1, w2, b2, w3 = (inp[k] for k in ("MLP_W1", "MLP_B1", "MLP_W2", "MLP_B2", "MLP_W3"))
    b3, ioff, igain, ooff, oscale = inp["MLP_NORM"]
    n = len(w1)
    gam = lambda k: k * U / (1 - k * U)  # noqa: E731
    out = []
    for x in temps:
        u_ = igain * (x - ioff)
        du = gam(3) * (abs(igain) * (abs(x) + abs(ioff)))
        z1 = [w1[j] * u_ + b1[j] for j in range(n)]
        a1 = [math.tanh(z) for z in z1]
        ea1 = [abs(w1[j]) * du + gam(3) * (abs(w1[j] * u_) + abs(b1[j])) + 2 * U for j in range(n)]
        d1 = [(1 - a1[j] ** 2) * w1[j] * igain for j in range(n)]
        ed1 = [2 * abs(a1[j]) * ea1[j] * abs(w1[j] * igain) + gam(4) * abs(d1[j]) + 2 * U * abs(w1[j] * igain) for j in range(n)]
        zo = b3
        ezo = gam(n + 2) * abs(b3)
        dzo = 0.0
        edzo = 0.0
        for j in range(n):
            row = w2[j * n : (j + 1) * n]
            s = b2[j] + sum(row[i] * a1[i] for i in range(n))
            es = sum(abs(row[i]) * ea1[i] for i in range(n)) + gam(n + 2) * (abs(b2[j]) + sum(abs(row[i] * a1[i]) for i in range(n)))
            ds = sum(row[i] * d1[i] for i in range(n))
            eds = sum(abs(row[i]) * ed1[i] for i in range(n)) + gam(n + 2) * sum(abs(row[i] * d1[i]) for i in range(n))
            a = math.tanh(s)
            ea = es + 2 * U
            fp = 1 - a * a
            efp = 2 * abs(a) * ea + gam(2)
            zo += w3[j] * a
            ezo += abs(w3[j]) * ea + gam(n + 2) * abs(w3[j] * a)
            dzo += w3[j] * fp * ds
            edzo += abs(w3[j]) * (efp * abs(ds) + abs(fp) * eds) + gam(n + 3) * abs(w3[j] * fp * ds)
        ey = abs(oscale) * ezo + gam(3) * (abs(ooff) + abs(oscale * zo))
        ed = abs(oscale) * edzo + gam(3) * abs(oscale * dzo)
        out.append((ey, ed))
    return out


def kappa(p_meas: list[float], r: list[float]) -> float:
    """Upper bound of κ(S), S = HPHᵀ + R: λmax ≤ tr(HPHᵀ) + max R, λmin ≥ min R."""
    return (sum(p_meas) + max(r)) / min(r)


class Checker:
    def __init__(self) -> None:
        self.failures: list[str] = []
        self.checked = 0

    def within(self, what: str, got: float, ref: float, bound: float) -> None:
        self.checked += 1
        if not (abs(got - ref) <= bound):
            self.failures.append(f"{what}: f32 {got!r} vs f64 {ref!r}: |diff| {abs(got - ref):.3e} > bound {bound:.3e}")

    def equal(self, what: str, got: float, ref: float) -> None:
        self.checked += 1
        if got != ref:
            self.failures.append(f"{what}: {got!r} != {ref!r}")


def group_max(recs: list[list[float]], cols: range, floor: float) -> float:
    return max([floor] + [abs(r[c]) for r in recs for c in cols])


def check_filter(ck: Checker, case: str, r32: list, r64: list, *, n_meas: int, r_meas: list[float], upd_at, floors: dict, offset: int) -> None:
    """ZUPT-family layout after `offset`: pos 3, vel 3, q 4, ba 3, bg 3, P diag 15."""
    o = offset
    groups = {
        "position": range(o, o + 3),
        "velocity": range(o + 3, o + 6),
        "attitude": range(o + 6, o + 10),
        "accel bias": range(o + 10, o + 13),
        "gyro bias": range(o + 13, o + 16),
    }
    pgroups = {name: range(o + 16 + 3 * i, o + 19 + 3 * i) for i, name in enumerate(["P position", "P velocity", "P attitude", "P accel bias", "P gyro bias"])}
    scale = {g: group_max(r64, cols, floors[g]) for g, cols in groups.items()}
    pscale = {g: group_max(r64, cols, 0.0) for g, cols in pgroups.items()}
    kap = max(kappa([r[o + 16 + i] for i in range(n_meas)], r_meas) for r in r64)
    c_upd = 2 * n_meas * kap
    for a, b in zip(r32, r64):
        ck.equal(f"{case} sample index", a[0], b[0])
        k = int(b[0]) + 1
        m = upd_at(b)
        t = k * DT
        load = 60 * k + c_upd * m
        att = U * (20 + 30 * k) + U * scale["attitude"] * c_upd * m
        bnd = {
            "attitude": att,
            "velocity": U * scale["velocity"] * load + G * t * att,
            "accel bias": U * scale["accel bias"] * load,
            "gyro bias": U * scale["gyro bias"] * load,
        }
        bnd["position"] = U * scale["position"] * load + t * bnd["velocity"]
        for g, cols in groups.items():
            for c in cols:
                ck.within(f"{case}[k={k - 1}] {g}[{c - o}]", a[c], b[c], bnd[g])
        for g, cols in pgroups.items():
            for c in cols:
                ck.within(f"{case}[k={k - 1}] {g}", a[c], b[c], U * pscale[g] * (32 * k + c_upd * m))


def check_precision(ck: Checker, v32: dict, v64: dict, inp: dict) -> None:
    # Attitude.
    for a, b in zip(records("attitude", v32["attitude"]), records("attitude", v64["attitude"])):
        k = int(b[0]) + 1
        for i in range(1, 5):
            ck.within(f"attitude[k={k - 1}] q[{i - 1}]", a[i], b[i], (20 + 30 * k) * U)
    # MLP.
    r32, r64 = records("mlp", v32["mlp"]), records("mlp", v64["mlp"])
    temps = [inp["STATIC_TEMP"][int(b[0])] for b in r64]
    for a, b, (ey, ed) in zip(r32, r64, mlp_bounds(inp, temps)):
        ck.within(f"mlp[k={int(b[0])}] value", a[1], b[1], ey)
        ck.within(f"mlp[k={int(b[0])}] derivative", a[2], b[2], ed)
    # ZUPT: R from the default configuration (1e-3 m, 1e-3 m/s, 1e-4 rad), update every 10.
    zr = [1e-6] * 6 + [1e-8] * 3
    floors = {"position": 1e-3, "velocity": 1e-3, "attitude": 1.0, "accel bias": 0.05, "gyro bias": 1e-3}
    check_filter(ck, "zupt", records("zupt", v32["zupt"]), records("zupt", v64["zupt"]), n_meas=9, r_meas=zr, upd_at=lambda b: (int(b[0]) + 1) // 10, floors=floors, offset=1)
    r32, r64 = records("tczupt", v32["tczupt"]), records("tczupt", v64["tczupt"])
    check_filter(ck, "tczupt", r32, r64, n_meas=9, r_meas=zr, upd_at=lambda b: (int(b[0]) + 1) // 100, floors=floors, offset=1)
    # dT/dt: the least-squares slope over the 1 s window (N = 100 samples, t spanning 1 s):
    # slope = Σ(t − t̄)(T − T̄)/Σ(t − t̄)², Σ|t − t̄| ≈ N/4 s, Σ(t − t̄)² ≈ N/12 s². Rounding
    # the temperatures to f32 moves it by ≤ u·|T|·3 /s; the running sums, updated on every
    # push, carry ≤ 2k·u·|T|·(N/2)/(N/12) = 12k·u·|T| /s.
    tmax = max(abs(x) for x in inp["STATIC_TEMP"])
    for a, b in zip(r32, r64):
        k = int(b[0]) + 1
        ck.within(f"tczupt[k={k - 1}] dT/dt", a[32], b[32], U * tmax * (3 + 12 * k))
    # INS: R from the fixes (σ floored by the configuration), GNSS updates as counted.
    r32, r64 = records("ins", v32["ins"]), records("ins", v64["ins"])
    fixes = inp["GNSS_FIXES"]
    fixes = [fixes[i : i + 10] for i in range(0, len(fixes), 10)]
    hs, vs, ss = max(f[7] for f in fixes), max(f[8] for f in fixes), max(f[9] for f in fixes)
    ir = [max(hs, 0.5) ** 2] * 2 + [max(vs, 0.5) ** 2] + [max(ss, 0.05) ** 2] * 3
    for a, b in zip(r32, r64):
        ck.equal(f"ins[k={int(b[0])}] fix status", a[1], b[1])
    # Compare in metres: turn latitude/longitude (rad) into metres for the position group.
    def to_m(rs: list) -> list:
        return [[r[0]] + [r[2] * EARTH_R, r[3] * EARTH_R, r[4]] + r[5:] for r in rs]

    # Positions are absolute (≈ 5e6 m after scaling): the group scale is what the corrections
    # and increments move, the σ of the fixes (2.5 m) and the distance flown (≤ 30 m).
    floors_ins = {"position": 30.0, "velocity": 1.0, "attitude": 1.0, "accel bias": 0.1, "gyro bias": 0.0035}
    n_upd = {}
    count = 0
    for b in r64:
        if b[1] >= 0:
            count += 1
        n_upd[id(b)] = count
    # Position in both builds is f64: only increments and corrections carry f32 error, so the
    # absolute value is subtracted from the group scale by comparing against the start.
    a32, a64 = to_m(r32), to_m(r64)
    base = a64[0][1:4]
    for rs in (a32, a64):
        for r in rs:
            for i in range(3):
                r[1 + i] -= base[i]
    mcount = iter([n_upd[id(b)] for b in r64])
    check_filter(ck, "ins", a32, a64, n_meas=6, r_meas=ir, upd_at=lambda b: next(mcount), floors=floors_ins, offset=0)
    # Static detector.
    acc = inp["FLIGHT_ACCEL"]
    gyr = inp["FLIGHT_GYRO"]
    amax = max(abs(math.sqrt(acc[3 * i] ** 2 + acc[3 * i + 1] ** 2 + acc[3 * i + 2] ** 2) - 9.80665) for i in range(len(acc) // 3))
    wmax = max(math.sqrt(gyr[3 * i] ** 2 + gyr[3 * i + 1] ** 2 + gyr[3 * i + 2] ** 2) for i in range(len(gyr) // 3))
    tmax = (9.80665 + amax) ** 2 / 0.05**2 + wmax**2 / 0.01**2
    for a, b in zip(records("detector", v32["detector"]), records("detector", v64["detector"])):
        k = int(b[0]) + 1
        bound = U * (2 * k + 20) * tmax
        ck.within(f"detector[k={k - 1}] statistic", a[1], b[1], bound)
        if abs(b[1] - 10.0) > bound:
            ck.equal(f"detector[k={k - 1}] decision", a[2], b[2])
    # FDI.
    zmax = max(abs(x) for x in inp["ARRAY_GYRO"]) + 0.05
    dr = (2 * 18 + 30) * U * zmax
    for a, b in zip(records("fdi", v32["fdi"]), records("fdi", v64["fdi"])):
        k = int(b[0])
        for i in range(1, 4):
            ck.within(f"fdi[k={k}] rate[{i - 1}]", a[i], b[i], dr)
        ck.within(f"fdi[k={k}] chi2", a[4], b[4], 2 * math.sqrt(18 * abs(b[4])) * dr / 2e-3 + 18 * U * abs(b[4]))
        for i in range(5, 13):
            ck.equal(f"fdi[k={k}] flag[{i - 5}]", a[i], b[i])


def check_position(ck: Checker, v32: dict, v64: dict) -> None:
    """Geodetic part: f64 in both builds, equal. Local NED position: one multiply and one add
    per step, |Δp| ≤ k·2u·|p|max + k·u·|v|·dt (the rounded velocity)."""
    r32, r64 = records("position", v32["position"]), records("position", v64["position"])
    pmax = max(abs(r[i]) for r in r64 for i in (6, 7, 8))
    for a, b in zip(r32, r64):
        k = int(b[0]) + 1
        for i in range(1, 6):
            ck.equal(f"position[k={k - 1}] geodetic[{i - 1}]", a[i], b[i])
        for i in range(6, 9):
            ck.within(f"position[k={k - 1}] ned[{i - 6}]", a[i], b[i], k * U * (2 * pmax + 10 * DT))


def run_qemu(machine: str, cpu: str, elf: str) -> tuple[str, int, float]:
    cmd = [
        "qemu-system-arm", "-machine", machine, "-cpu", cpu, "-nographic", "-monitor", "none",
        "-serial", "none", "-semihosting-config", "enable=on,target=native", "-icount", "shift=0",
        "-kernel", elf,
    ]  # fmt: skip
    t0 = time.monotonic()
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600, check=False)
    return p.stdout + p.stderr, p.returncode, time.monotonic() - t0


def symbol_sizes(nm: str, elf: str) -> dict[str, int]:
    """Code bytes per nav-core module (demangled symbol paths), from ``llvm-nm -S``."""
    out = subprocess.run([nm, "-S", "--size-sort", "-C", elf], capture_output=True, text=True, check=True).stdout
    sizes: dict[str, int] = defaultdict(int)
    for line in out.splitlines():
        w = line.split(maxsplit=3)
        if len(w) < 4 or w[2].lower() not in ("t", "r"):
            continue
        name = w[3]
        size = int(w[1], 16)
        for mod in ("zupt", "ins", "mlp", "attitude", "redundancy", "strapdown", "earth"):
            if f"nav_core::{mod}" in name:
                sizes[mod] += size
                break
        else:
            if "libm::" in name or "compiler_builtins" in name or name.startswith("__aeabi") or "__adddf3" in name:
                sizes["libm + soft-float"] += size
            elif "nalgebra::" in name:
                sizes["nalgebra (not inlined)"] += size
            else:
                sizes["other (harness, core, fmt)"] += size
    return sizes


PANIC = re.compile(r"bl\s+0x[0-9a-f]+\s+<(core::panicking::[^>]+|core::slice::index::[^>]+|core::option::[^>]+|core::result::[^>]+)>")


def panic_sites(objdump: str, elf: str) -> list[tuple[str, str]]:
    """(calling function, panic function) for every call into core's panic paths."""
    out = subprocess.run([objdump, "-d", "-C", "--no-show-raw-insn", elf], capture_output=True, text=True, check=True).stdout
    func = "?"
    sites = []
    for line in out.splitlines():
        m = re.match(r"^[0-9a-f]+ <(.*)>:$", line)
        if m:
            func = m.group(1)
            continue
        m = PANIC.search(line)
        if m:
            sites.append((func, m.group(1)))
    return sites


def write_c_inputs(path: str) -> None:
    """``inputs.h`` for the C interface test: the arrays of ``src/inputs.rs`` as C doubles."""
    text = (HERE / "src" / "inputs.rs").read_text()
    lines = ["/* Written by crates/nav-firmware/check.py from src/inputs.rs. */"]
    for m in re.finditer(r"pub static (\w+): ([^=]+)= \[(.*?)\];", text, re.S):
        name, ty, body = m.groups()
        dims = re.findall(r"; (\d+)\]", ty)
        vals = re.findall(r"[-+0-9.eE]+(?:e[-+]?\d+)?", body)
        decl = "".join(f"[{d}]" for d in reversed(dims))
        if len(dims) == 2:
            w = int(dims[0])
            rows = [", ".join(vals[i : i + w]) for i in range(0, len(vals), w)]
            init = ", ".join(f"{{{r}}}" for r in rows)
        else:
            init = ", ".join(vals)
        lines.append(f"static const double {name}{decl} = {{{init}}};")
    Path(path).write_text("\n".join(lines) + "\n")


def check_c_output(path: str, ref: dict) -> bool:
    """The C program's outputs equal the host reference's f32 outputs bit for bit."""
    text = Path(path).read_text()
    vals, _, _ = parse(text)
    if "done" not in text.split():
        print(f"error: the C interface test did not finish: {text[-300:]}")
        return False
    bad, n = [], 0
    for case, got in vals["f32"].items():
        want = ref["f32"][case]
        if len(got) != len(want):
            bad.append(f"{case}: {len(got)} values, host {len(want)}")
            continue
        for i, (a, b) in enumerate(zip(got, want)):
            n += 1
            if struct.pack("<d", a) != struct.pack("<d", b):
                bad.append(f"{case}[{i}]: {a!r} != host {b!r}")
    if bad or n == 0:
        print(f"error: the C interface differs from the host reference in {len(bad)} of {n} values:")
        for line in bad[:20]:
            print(f"  {line}")
        return False
    print(f"C interface (gcc, nav-ffi): {n} values of {', '.join(vals['f32'])} bit-identical to the host reference")
    return True


def main() -> int:
    if len(sys.argv) == 3 and sys.argv[1] == "c-inputs":
        write_c_inputs(sys.argv[2])
        return 0
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("host")
    ap.add_argument("m4")
    ap.add_argument("m7")
    ap.add_argument("--size", default="llvm-size")
    ap.add_argument("--nm", default="llvm-nm")
    ap.add_argument("--objdump", default="llvm-objdump")
    ap.add_argument("--c-output", help="output of the C interface test, compared with the host")
    args = ap.parse_args()

    host = subprocess.run([args.host], capture_output=True, text=True, check=False)
    if host.returncode != 0:
        print(f"error: host reference failed: {host.stderr.strip()}")
        return 1
    ref, _, _ = parse(host.stdout)
    inp = inputs()
    ok = True
    runs = {}
    for key, machine, cpu, elf in (("m4", "mps2-an386", "cortex-m4", args.m4), ("m7", "mps2-an500", "cortex-m7", args.m7)):
        text, rc, secs = run_qemu(machine, cpu, elf)
        vals, timing, cal = parse(text)
        errors = [line for line in text.splitlines() if line.startswith(("error", "panicked"))]
        if rc != 0 or "done" not in text.split():
            print(f"error: firmware on {machine} ({cpu}) failed (exit {rc}): {' | '.join(errors) or text[-500:]}")
            ok = False
            continue
        mism = []
        n = 0
        for prec in ("f32", "f64"):
            for case, v in ref[prec].items():
                got = vals[prec].get(case, [])
                if len(got) != len(v):
                    mism.append(f"{prec} {case}: {len(got)} values, host {len(v)}")
                    continue
                for i, (a, b) in enumerate(zip(got, v)):
                    n += 1
                    if struct.pack("<d", a) != struct.pack("<d", b):
                        mism.append(f"{prec} {case}[{i}]: {a!r} != host {b!r}")
        if mism:
            ok = False
            print(f"error: {machine} ({cpu}) differs from the host in {len(mism)} of {n} values:")
            for line in mism[:20]:
                print(f"  {line}")
        else:
            print(f"{machine} ({cpu}): {n} values bit-identical to the host reference ({secs:.1f} s in QEMU)")
        runs[key] = (timing, cal)

    if args.c_output and not check_c_output(args.c_output, ref):
        ok = False

    ck = Checker()
    check_precision(ck, ref["f32"], ref["f64"], inp)
    check_position(ck, ref["f32"], ref["f64"])
    if ck.failures:
        ok = False
        print(f"error: {len(ck.failures)} of {ck.checked} f32 outputs outside their derived bound:")
        for line in ck.failures[:20]:
            print(f"  {line}")
    else:
        print(f"f32 vs f64: {ck.checked} outputs within their derived bounds")

    if "m4" in runs and "m7" in runs:
        print_budget(runs)
        print_sizes(args)
    return 0 if ok else 1


# Steps of the table: per-call rows, then the worst sample of each filter (both calls in one
# sample period).
COMPOSITE = {
    "ZUPT sample with update": ("zupt.predict", "zupt.update"),
    "INS sample with GNSS fix": ("ins.predict", "ins.update_gnss"),
}
ROWS = [
    ("attitude.step", "AHRS attitude step"),
    ("zupt.predict", "ZUPT predict"),
    ("zupt.update", "ZUPT update (9 rows)"),
    ("mlp.eval", "MLP value + dy/dT"),
    ("tczupt.step", "TCZUPT step (slope, MLP, predict)"),
    ("tczupt.step+update", "TCZUPT step with update"),
    ("ins.predict", "INS predict (f64 position)"),
    ("ins.update_gnss", "INS GNSS update (6 rows)"),
    ("detector.push", "static detector"),
    ("fdi.step", "FDI, 6 triaxial gyros"),
    ("position.geodetic_f64", "INS position part: f64 lat/lon/h + Earth refresh"),
    ("position.local", "same, PX4-style NED from a local origin (precision of the column)"),
]


def instr(timing: dict, cal: dict, step: str, what: str = "max") -> float:
    t = timing[step]
    ticks = t["sum"] / t["calls"] if what == "mean" else t[what]
    return ticks * cal["instructions"] / cal["ticks"]


def fmt_rate(hz: float) -> str:
    return f"{hz / 1000:.1f} kHz" if hz >= 1000 else f"{hz:.0f} Hz"


def print_budget(runs: dict) -> None:
    print()
    print("Instructions per call (QEMU -icount shift=0, SysTick), cycles = instructions × CPI range")
    print("(an estimate), highest IMU rate with the worst call in 25 % of the core; stack = high-water mark.")
    cols = [("m4", "f32"), ("m7", "f32"), ("m7", "f64"), ("m4", "f64")]
    head = "| step | " + " | ".join(f"{BOARDS[b][0].split()[0]} {p}: instr mean / max, stack, max rate" for b, p in cols) + " |"
    print(head)
    print("|" + "---|" * (1 + len(cols)))
    rows = list(ROWS) + [(k, k) for k in COMPOSITE]
    for step, label in rows:
        cells = []
        for b, p in cols:
            timing, cal = runs[b]
            tp = timing[p]
            if step in COMPOSITE:
                parts = COMPOSITE[step]
                mean = sum(instr(tp, cal, s, "mean") for s in parts)
                mx = sum(instr(tp, cal, s) for s in parts)
                stack = max(tp[s]["stack"] for s in parts)
            else:
                mean, mx, stack = instr(tp, cal, step, "mean"), instr(tp, cal, step), tp[step]["stack"]
            _, hz, (clo, chi) = BOARDS[b]
            rate_lo = BUDGET * hz / (mx * chi)
            rate_hi = BUDGET * hz / (mx * clo)
            cells.append(f"{mean:,.0f} / {mx:,.0f}, {stack:,} B, {fmt_rate(rate_lo)}–{fmt_rate(rate_hi)}")
        print(f"| {label} | " + " | ".join(cells) + " |")
    print()
    for b, p, step, rate in (("m4", "f32", "ZUPT sample with update", 1000), ("m4", "f32", "attitude.step", 1000), ("m4", "f32", "INS sample with GNSS fix", 400), ("m7", "f32", "ZUPT sample with update", 1000), ("m7", "f32", "INS sample with GNSS fix", 400), ("m7", "f64", "ZUPT sample with update", 1000), ("m7", "f64", "INS sample with GNSS fix", 400)):
        timing, cal = runs[b]
        tp = timing[p]
        parts = COMPOSITE.get(step, (step,))
        mx = sum(instr(tp, cal, s) for s in parts)
        _, hz, (clo, chi) = BOARDS[b]
        share = (mx * chi * rate / hz, mx * clo * rate / hz)
        verdict = "fits" if share[0] <= BUDGET else ("fits only at the low CPI" if share[1] <= BUDGET else "does NOT fit")
        print(f"{BOARDS[b][0]} {p}: {step} at {rate} Hz uses {100 * share[1]:.1f}–{100 * share[0]:.1f} % of the core: {verdict} in 25 %")


def print_sizes(args: argparse.Namespace) -> None:
    for key, elf in (("m4", args.m4), ("m7", args.m7)):
        try:
            total = subprocess.run([args.size, "-A", elf], capture_output=True, text=True, check=True).stdout
            sizes = symbol_sizes(args.nm, elf)
            sites = panic_sites(args.objdump, elf)
        except (OSError, subprocess.CalledProcessError) as e:
            print(f"error: size tools: {e}")
            continue
        sec = {w[0]: int(w[1]) for w in (line.split() for line in total.splitlines()) if len(w) >= 2 and w[0].startswith(".") and w[1].isdigit()}
        print()
        print(f"{BOARDS[key][0]} firmware (f32 and f64 cases, harness included): .text {sec.get('.text', 0):,} B, .rodata {sec.get('.rodata', 0):,} B (inputs), .data+.bss {sec.get('.data', 0) + sec.get('.bss', 0):,} B")
        print("  code per module (f32 + f64 instances, non-inlined symbols): " + ", ".join(f"{k} {v:,} B" for k, v in sorted(sizes.items(), key=lambda kv: -kv[1])))
        print(f"  panic call sites: {len(sites)} (calls into core::panicking and friends), by owner:")
        by_owner: dict[str, dict[str, set]] = defaultdict(lambda: defaultdict(set))
        for func, kind in sites:
            name = re.sub(r"::h[0-9a-f]{16}$", "", func).replace("$LT$", "<").replace("$GT$", ">")
            m = re.match(r"(?:uasnav_)?nav_core::(\w+)", name)
            owner = f"nav-core {m.group(1)}" if m else next((o for o in ("libm", "nalgebra", "nav_firmware", "core") if o in name), "other")
            by_owner[owner][kind.split("::")[-1].split("<")[0]].add(name)
        for owner, kinds in sorted(by_owner.items()):
            funcs = sorted({f for fs in kinds.values() for f in fs if owner.startswith("nav-core")})
            print(f"    {owner}: " + ", ".join(f"{k} in {len(v)} fn" for k, v in sorted(kinds.items())) + (f" ({'; '.join(funcs)})" if funcs else ""))

if __name__ == "__main__":
    sys.exit(main())
