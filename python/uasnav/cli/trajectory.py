"""``uasnav trajectory``: train, predict and evaluate LVQ element-time models (thesis §5.1)."""

from __future__ import annotations

import math

import click
import numpy as np

from uasnav.cli._common import (
    NON_NEGATIVE,
    POSITIVE,
    SEED,
    OutputPath,
    check_outputs,
    echo_json,
    parse_float_list,
)
from uasnav.errors import InputError


def parse_wind(text: str) -> np.ndarray:
    """``SPEED@DIR`` → wind velocity (north, east) m/s; DIR is where the wind comes *from* (deg)."""
    from uasnav.trajectory.features import wind_vector

    try:
        speed, direction = (float(x) for x in text.split("@"))
    except ValueError:
        raise InputError(
            f"--wind must be SPEED@DIR (m/s @ deg from north, wind from), got {text!r}"
        ) from None
    # 100 m/s is beyond any wind a small UAS flies in: larger values are typos (or overflow).
    if not (math.isfinite(speed) and math.isfinite(direction) and 0.0 <= speed <= 100.0):
        raise InputError(
            f"--wind: SPEED must be in [0, 100] m/s and DIR finite (deg from north), got {text!r}"
        )
    return wind_vector(speed, direction)


@click.group("trajectory")
def command() -> None:
    """Trajectory prediction with LVQ networks: element times, ETA and 4D waypoint times."""


_common_opts = [
    click.option(
        "--plan", type=click.Path(dir_okay=False), help="Plan CSV (lat,lon,alt) for logs without a mission."
    ),
    click.option(
        "--speed", type=POSITIVE, help="Commanded speed (m/s); default from the log (WPNAV_SPEED …)."
    ),
    click.option(
        "--wind", "wind_text", help="Wind SPEED@DIR (m/s, deg wind comes from); default the log's or calm."
    ),
    click.option("--segment", type=POSITIVE, default=10.0, show_default=True, help="Segment length L (m)."),
    click.option(
        "--max-gap",
        type=POSITIVE,
        default=5.0,
        show_default=True,
        help="Largest telemetry gap in an element (s).",
    ),
]


def _apply(opts):  # type: ignore[no-untyped-def]
    def deco(f):  # type: ignore[no-untyped-def]
        for o in reversed(opts):
            f = o(f)
        return f

    return deco


@command.command("train")
@click.argument("flights", nargs=-1, required=True, type=click.Path())
@click.option("--out", "out", required=True, type=OutputPath(), help="Model JSON to write.")
@_apply(_common_opts)
@click.option("--algorithm", type=click.Choice(["lvq1", "lvq2.1", "glvq"]), default="lvq1", show_default=True)
@click.option(
    "--prototypes", type=click.IntRange(1), default=256, show_default=True, help="Competitive neurons S¹."
)
@click.option("--seed", type=SEED, default=0, show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
def train(flights, out, plan, speed, wind_text, segment, max_gap, algorithm, prototypes, seed, as_json):  # type: ignore[no-untyped-def]
    """Train a model on the flown elements of FLIGHT... (.tlog, .bin, .ulg, .csv, or element
    datasets .parquet from `uasnav fleet elements`) and write it."""
    from uasnav.trajectory.element_table import training_samples
    from uasnav.trajectory.predictor import TrajectoryPredictor

    check_outputs([*flights, plan], {"--out": out})
    wind = parse_wind(wind_text) if wind_text else None
    # flight logs and/or element datasets (.parquet, e.g. from `uasnav fleet elements`)
    all_s, n_runs = training_samples(flights, plan, speed, wind, segment, max_gap)
    import warnings

    from uasnav.trajectory.baselines import class_method_reason

    why = class_method_reason(all_s.cell, "populated feature cells")
    if why is not None:
        # Say it once, in our words (the same rule `evaluate` reports as "not applicable"),
        # instead of scikit-learn's "number of unique classes is greater than 50%" UserWarning.
        click.echo(f"warning: {why}", err=True)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="The number of unique classes", category=UserWarning)
        model = TrajectoryPredictor(segment, prototypes, algorithm, random_state=seed).fit(all_s)
    model.save(out)
    info = {
        "model": out,
        "n_runs": n_runs,
        "n_elements": len(all_s),
        "n_classes": int((model.count_table_ > 0).sum()),
        "cruise_ms": model.cruise_ms_,
    }
    if as_json:
        echo_json(info)
    else:
        click.echo(
            f"trained on {info['n_elements']} elements of {info['n_runs']} run(s), "
            f"{info['n_classes']} populated classes → {out}"
        )


@command.command("predict")
@click.option("--model", "model_path", required=True, type=click.Path(dir_okay=False))
@click.option("--plan", "plan_path", required=True, type=click.Path(dir_okay=False))
@click.option("--wind", "wind_text", required=True, help="SPEED@DIR: m/s @ degrees the wind comes from.")
@click.option("--speed", type=POSITIVE, help="Commanded speed (m/s); default the model's.")
@click.option("--required", help="4D plan: required time (s from start) at each waypoint, T0,T1,….")
@click.option("--tolerance", type=NON_NEGATIVE, default=5.0, show_default=True, help="4D time tolerance (s).")
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
def predict(model_path, plan_path, wind_text, speed, required, tolerance, as_json):  # type: ignore[no-untyped-def]
    """Per-element times, ETA and 4D waypoint times of PLAN (CSV lat,lon,alt or north,east).

    With --required, also checks the 4D plan's feasibility: each waypoint reached within
    --tolerance of its required time (exit code 0 either way; see "feasible").
    """
    from uasnav.trajectory.plans import read_plan
    from uasnav.trajectory.predictor import TrajectoryPredictor

    # options first, files second: a typo in an option is reported before any file is read
    wind = parse_wind(wind_text)
    req = parse_float_list(required, "--required") if required else None
    model = TrajectoryPredictor.load(model_path)
    plan_ne, _ = read_plan(plan_path)
    p = model.predict(plan_ne, wind, speed)
    feas = None
    if req is not None:
        feas = model.feasibility(plan_ne, np.array(req), wind, tolerance, speed)
    el, f = p.elements, p.features
    rows = [
        {
            "element": i,
            "kind": str(el.kind[i]),
            "length_m": float(el.length_m[i]),
            "theta_deg": float(f.theta_deg[i]),
            "theta_w_deg": float(f.theta_w_deg[i]),
            "wind_ms": float(f.wind_ms[i]),
            "class": int(p.cell_used[i]),
            "dv_ms": float(p.dv_ms[i]),
            "time_s": float(p.time_s[i]),
            "low_confidence": bool(p.flags[i]),
            "flags": p.flags[i],
        }
        for i in range(len(el))
    ]
    if as_json:
        out = {"eta_s": p.eta_s, "waypoint_times_s": p.waypoint_times_s, "elements": rows}
        if feas is not None:
            out["feasible"] = feas.feasible
            out["waypoint_ok"] = feas.ok
        echo_json(out)
        return
    click.echo(f"{'#':>3} {'kind':8} {'L m':>6} {'θ°':>6} {'θw°':>6} {'ΔV m/s':>7} {'t s':>7}")
    for r in rows:
        mark = "  *low confidence: " + "; ".join(r["flags"]) if r["flags"] else ""
        click.echo(
            f"{r['element']:>3} {r['kind']:8} {r['length_m']:6.1f} {r['theta_deg']:6.1f} "
            f"{r['theta_w_deg']:6.1f} {r['dv_ms']:7.2f} {r['time_s']:7.2f}{mark}"
        )
    click.echo(
        f"ETA {p.eta_s:.1f} s; waypoint times (s): " + ", ".join(f"{x:.1f}" for x in p.waypoint_times_s)
    )


@command.command("evaluate")
@click.argument("flights", nargs=-1, type=click.Path(dir_okay=False))
@_apply(_common_opts)
@click.option("--simulated", is_flag=True, help="Run the simulated Phantom-4 experiment (Table 17) instead.")
@click.option("--seed", type=SEED, default=0, show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
def evaluate(flights, plan, speed, wind_text, segment, max_gap, simulated, seed, as_json):  # type: ignore[no-untyped-def]
    """e% (eq. 59) per element and per run of LVQ vs the baselines.

    Real FLIGHT...: leave-one-run-out (each mission run predicted by a model trained on the
    others). --simulated: the thesis' experiment, 7 flights per trajectory train, 3 test.
    """
    if simulated:
        from uasnav.experiments.trajectory import run_phantom4

        r = run_phantom4(seed=seed)
        table = {
            m.name: {
                "applicable": True,
                "element_e_pct_mean": float(m.error_pct.mean()),
                "element_e_pct_max": float(m.error_pct.max()),
            }
            if m.applicable
            else {"applicable": False, "reason": m.reason}
            for m in r.methods
        }
        t17 = [{"piece": p.piece, "t_nn_s": p.t_nn_s, "t_real_s": list(p.t_real_s)} for p in r.table17]
        out = {"methods": table, "table17": t17, "n_train": len(r.train), "n_test": len(r.test)}
    else:
        from uasnav.trajectory.flights import flight_samples, leave_one_run_out

        if not flights:
            raise click.UsageError("give FLIGHT files or --simulated")
        wind = parse_wind(wind_text) if wind_text else None
        fs = flight_samples(flights, plan, speed, wind, segment, max_gap)
        table = {
            e.name: {
                "applicable": True,
                "element_e_pct_mean": float(np.mean(e.element_pct)),
                "element_e_pct_median": float(np.median(e.element_pct)),
                "run_e_pct_mean": float(np.mean(e.run_pct)),
                "run_e_pct": list(e.run_pct),
            }
            if e.applicable
            else {"applicable": False, "reason": e.reason}
            for e in leave_one_run_out(fs, segment, random_state=seed)
        }
        out = {"methods": table, "n_runs": len(fs), "n_elements": fs.n_elements}
    if as_json:
        echo_json(out)
        return
    for name, d in out["methods"].items():
        if not d["applicable"]:
            click.echo(f"{name:24s} not applicable: {d['reason']}")
            continue
        extra = f"  run e% {d['run_e_pct_mean']:6.2f}" if "run_e_pct_mean" in d else ""
        click.echo(f"{name:24s} element e% mean {d['element_e_pct_mean']:6.2f}{extra}")
    for row in out.get("table17", []):
        click.echo(
            f"{row['piece']}: t_NN {row['t_nn_s']:.2f} s, t_Real "
            + ", ".join(f"{x:.2f}" for x in row["t_real_s"])
        )
