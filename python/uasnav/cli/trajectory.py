"""``uasnav trajectory``: train, predict and evaluate LVQ element-time models (thesis §5.1)."""

from __future__ import annotations

import math
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click
import numpy as np

from uasnav.cli._common import (
    BUFFER_M,
    NON_NEGATIVE,
    POSITIVE,
    PROBABILITY,
    SEED,
    UAS_SPEED,
    OutputPath,
    Real,
    check_outputs,
    echo_json,
    parse_float_list,
    warnings_after_success,
)
from uasnav.errors import DataFormatError, InputError

if TYPE_CHECKING:
    from uasnav.io.autopilot_limits import AutopilotLimits


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
    """Trajectory prediction (kinematic point mass with the autopilot's limits, or the thesis'
    LVQ networks): element times, ETA, 4D waypoint times, time bounds, operational intents."""


_common_opts = [
    click.option(
        "--plan", type=click.Path(dir_okay=False), help="Plan CSV (lat,lon,alt) for logs without a mission."
    ),
    click.option(
        "--speed", type=UAS_SPEED, help="Commanded speed (m/s); default from the log (WPNAV_SPEED …)."
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


def _method_option(f):  # type: ignore[no-untyped-def]
    from uasnav.trajectory.models import DEFAULT_METHOD, METHODS

    return click.option(
        "--method",
        type=click.Choice(list(METHODS)),
        default=DEFAULT_METHOD,
        show_default=True,
        help="Predictor: kinematic point mass with the autopilot's limits (most accurate by "
        "leave-one-run-out on real flights) or the thesis' LVQ network.",
    )(f)


def _limits_source(lim: AutopilotLimits, log: str | None) -> str:
    """Which limits came from which log (``log``, see :func:`_log_limits`), for the model file."""
    if not lim.source:
        return "defaults"
    kinematic = {"accel_ms2", "climb_ms", "descent_ms", "accel_z_ms2"}
    rest = "" if kinematic <= set(lim.source) else "; others defaults"
    return f"{', '.join(lim.source)} from {log or 'log'}{rest}"


@command.command("train")
@click.argument("flights", nargs=-1, required=True, type=click.Path())
@click.option("--out", "out", required=True, type=OutputPath(), help="Model JSON to write.")
@_apply(_common_opts)
@click.option("--algorithm", type=click.Choice(["lvq1", "lvq2.1", "glvq"]), default="lvq1", show_default=True)
@click.option(
    "--prototypes", type=click.IntRange(1), default=256, show_default=True, help="Competitive neurons S¹."
)
@click.option("--seed", type=SEED, default=0, show_default=True)
@_method_option
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
def train(
    flights, out, plan, speed, wind_text, segment, max_gap, algorithm, prototypes, seed, method, as_json
):  # type: ignore[no-untyped-def]
    """Train a model on the flown elements of FLIGHT... (.tlog, .bin, .ulg, .csv, or element
    datasets .parquet from `uasnav fleet elements`) and write it.

    --method kinematic (default: the most accurate by leave-one-run-out on real flights) keeps
    the logs' autopilot limits (WPNAV_*, MPC_*) and the flights' speed; --method lvq trains the
    thesis' LVQ network (--algorithm, --prototypes; giving either selects it).
    """
    from uasnav.trajectory.element_table import training_samples
    from uasnav.trajectory.kinematic import KinematicPredictor
    from uasnav.trajectory.predictor import TrajectoryPredictor

    check_outputs([*flights, plan], {"--out": out})
    # the LVQ network's own options select it when no method is named
    src = click.get_current_context().get_parameter_source
    lvq_opts = [
        f"--{n}" for n in ("algorithm", "prototypes") if src(n) == click.core.ParameterSource.COMMANDLINE
    ]
    if lvq_opts and method != "lvq":
        if src("method") == click.core.ParameterSource.COMMANDLINE:
            raise click.UsageError(f"{', '.join(lvq_opts)} apply to --method lvq only")
        method = "lvq"
    wind = parse_wind(wind_text) if wind_text else None
    from uasnav.trajectory.baselines import class_method_reason

    # warnings (telemetry gaps) are shown once training succeeded: a failed run prints its one
    # error line only
    with warnings_after_success():
        # flight logs and/or element datasets (.parquet, e.g. from `uasnav fleet elements`)
        opened: dict[str, Any] = {}
        all_s, n_runs = training_samples(flights, plan, speed, wind, segment, max_gap, opened=opened)
        why = None
        model: KinematicPredictor | TrajectoryPredictor
        if method == "lvq":
            why = class_method_reason(all_s.cell, "populated feature cells")
            with warnings.catch_warnings():
                # said once below in our words (the rule `evaluate` reports as "not applicable")
                # instead of scikit-learn's "number of unique classes is greater than 50%"
                warnings.filterwarnings(
                    "ignore", message="The number of unique classes", category=UserWarning
                )
                model = TrajectoryPredictor(segment, prototypes, algorithm, random_state=seed).fit(all_s)
        else:
            lim, lim_log = _log_limits(flights, opened)
            model = KinematicPredictor(
                segment, lim.accel_ms2 or 1.0, lim.climb_ms or 2.5, lim.descent_ms or 1.5,
                accel_z_ms2=lim.accel_z_ms2 or 1.0, limits_source=_limits_source(lim, lim_log),
            ).fit(all_s)  # fmt: skip
    if why is not None:
        click.echo(f"warning: {why}", err=True)
    model.save(out)
    info = {
        "model": out,
        "method": method,
        "n_runs": n_runs,
        "n_elements": len(all_s),
        "n_classes": int((model.count_table_ > 0).sum()),
        "cruise_ms": model.cruise_ms_,
    }
    if isinstance(model, KinematicPredictor):
        info["limits"] = {
            "accel_ms2": model.accel_ms2,
            "climb_ms": model.climb_ms,
            "descent_ms": model.descent_ms,
            "accel_z_ms2": model.accel_z_ms2,
            "source": model.limits_source,
        }
    if as_json:
        echo_json(info)
    else:
        click.echo(
            f"trained {method} model on {info['n_elements']} elements of {info['n_runs']} run(s), "
            f"{info['n_classes']} populated classes → {out}"
        )


@command.command("predict")
@click.option("--model", "model_path", required=True, type=click.Path(dir_okay=False))
@click.option("--plan", "plan_path", required=True, type=click.Path(dir_okay=False))
@click.option("--wind", "wind_text", required=True, help="SPEED@DIR: m/s @ degrees the wind comes from.")
@click.option("--speed", type=UAS_SPEED, help="Commanded speed (m/s); default the model's.")
@click.option("--required", help="4D plan: required time (s from start) at each waypoint, T0,T1,….")
@click.option("--tolerance", type=NON_NEGATIVE, default=5.0, show_default=True, help="4D time tolerance (s).")
@click.option(
    "--route",
    "route3d",
    is_flag=True,
    help="Time the plan's 3D route: take-off, legs, turns, climbs, descents, holds, landing.",
)
@click.option(
    "--home-alt",
    type=Real(-1000.0, 9000.0),
    help="With --route: home altitude AMSL (m) if the plan has none and mixes relative and AMSL "
    "altitudes (an AMSL plan's take-off and landing on the ground are relative to home).",
)
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
def predict(model_path, plan_path, wind_text, speed, required, tolerance, route3d, home_alt, as_json):  # type: ignore[no-untyped-def]
    """Per-element times, ETA and 4D waypoint times of PLAN (CSV lat,lon,alt or north,east).

    With --required, also checks the 4D plan's feasibility: each waypoint reached within
    --tolerance of its required time (exit code 0 either way; see "feasible"). With --route,
    the plan's whole 3D route (a geodetic mission plan) element by element, each with its kind
    (leg, turn, climb, descent, hover) and climb rate; vertical limits from a kinematic model.
    """
    if route3d:
        if required is not None:
            raise click.UsageError("--required applies to the horizontal plan, not with --route")
        _predict_route(model_path, plan_path, wind_text, speed, home_alt, as_json)
        return
    if home_alt is not None:
        raise click.UsageError("--home-alt applies to the 3D route: give --route too")
    from uasnav.io.plans import read_plan_route
    from uasnav.trajectory.models import load_model, method_of

    # options first, files second: a typo in an option is reported before any file is read
    wind = parse_wind(wind_text)
    req = parse_float_list(required, "--required") if required else None
    from uasnav.limits import PREDICTION_OPS_PER_POINT, check_work

    plan_ne, _ = read_plan_route(plan_path, other_as_csv=True)
    # estimated before the model is even read: a plan of 10⁵ points costs minutes of CPU
    check_work(
        len(plan_ne) * PREDICTION_OPS_PER_POINT, f"{plan_path}: a prediction of {len(plan_ne)} plan points"
    )
    model = load_model(model_path)
    p = model.predict(plan_ne, wind, speed)
    feas = None
    if req is not None:
        feas = model.feasibility(plan_ne, np.array(req), wind, tolerance, speed)
    rows = p.element_rows()
    if as_json:
        out = {
            "method": method_of(model),
            "eta_s": p.eta_s,
            "waypoint_times_s": p.waypoint_times_s,
            "elements": rows,
        }
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
        f"ETA {p.eta_s:.1f} s ({method_of(model)} model); waypoint times (s): "
        + ", ".join(f"{x:.1f}" for x in p.waypoint_times_s)
    )


def _predict_route(
    model_path: str,
    plan_path: str,
    wind_text: str,
    speed: float | None,
    home_alt: float | None,
    as_json: bool,
) -> None:
    """``predict --route``: the 3D elements of a geodetic plan."""
    from uasnav.io.plans import plan_cruise_speed, read_plan
    from uasnav.trajectory.models import load_model, method_of
    from uasnav.trajectory.route3d import predict_route, route_from_plan

    wind = parse_wind(wind_text)
    model = load_model(model_path)
    plan = read_plan(plan_path)
    route = route_from_plan(plan, home_amsl_m=home_alt)
    v = speed or plan_cruise_speed(plan) or model.cruise_ms_
    p = predict_route(model, route, wind, v)
    rows = p.elements.rows()
    if as_json:
        echo_json(
            {
                "method": method_of(model),
                "eta_s": p.eta_s,
                "arrive_s": p.t_arrive_s,
                "depart_s": p.t_depart_s,
                "elements": rows,
            }
        )
        return
    click.echo(f"{'#':>3} {'kind':8} {'seg':>4} {'L m':>6} {'dz m':>6} {'climb m/s':>9} {'t s':>7}")
    for r in rows:
        mark = "  *low confidence: " + "; ".join(r["flags"]) if r["flags"] else ""
        click.echo(
            f"{r['element']:>3} {r['kind']:8} {r['segment']:>4} {r['length_m']:6.1f} {r['dz_m']:6.1f} "
            f"{r['climb_rate_ms']:9.2f} {r['time_s']:7.2f}{mark}"
        )
    click.echo(f"ETA {p.eta_s:.1f} s ({method_of(model)} model, {len(route)} route points)")


def _log_limits(flights: Sequence[str], logs: Any) -> tuple[AutopilotLimits, str | None]:
    """The autopilot limits of the first log among ``flights`` that carries an acceleration
    limit, completed with the defaults (CSV flights carry no parameters), and that log's name
    (None: all defaults). ``logs`` are the logs as opened by ``flight_samples`` (path → LogFile):
    their limits come from the same decoding pass."""
    from uasnav.io.autopilot_limits import AutopilotLimits

    for f in flights:
        if str(f) in logs:
            lim = logs[str(f)].limits
            if lim.accel_ms2 is not None:
                return lim.or_defaults(), Path(f).name
    return AutopilotLimits().or_defaults(), None


@command.command("evaluate")
@click.argument("flights", nargs=-1, type=click.Path())
@_apply(_common_opts)
@click.option("--simulated", is_flag=True, help="Run the simulated Phantom-4 experiment (Table 17) instead.")
@click.option("--seed", type=SEED, default=0, show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
def evaluate(flights, plan, speed, wind_text, segment, max_gap, simulated, seed, as_json):  # type: ignore[no-untyped-def]
    """ETA and per-waypoint errors of the predictors on real flights, or the thesis' experiment.

    Real FLIGHT... (.tlog, .bin, .ulg with their mission): every AUTO run predicted by the
    autopilot's mission execution model with the log's own parameters (one flight is enough;
    no training), beside QGroundControl's mission-time estimate and plan length ÷ speed; the
    element methods (LVQ, kinematic point mass …, e% of eq. 59) by leave-one-run-out where the
    logs hold two runs or more; the model's own choices (its options, a learned scale, or a
    baseline) re-made on the other runs and scored on each held-out run and each held-out log.
    --simulated: the thesis' experiment, 7 flights per trajectory train, 3 test.
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
        if not flights:
            raise click.UsageError("give FLIGHT files or --simulated")
        out = _evaluate_flights(flights, plan, speed, wind_text, segment, max_gap, seed)
    if as_json:
        echo_json(out)
        return
    for name, d in out["methods"].items():
        if not d["applicable"]:
            click.echo(f"{name:24s} not applicable: {d['reason']}")
            continue
        extra = (
            f"  run |e%| median {d['run_abs_e_pct_median']:6.2f} p95 {d['run_abs_e_pct_p95']:6.2f} "
            f"worst {d['run_abs_e_pct_worst']:6.2f}"
            if "run_abs_e_pct_median" in d
            else ""
        )
        element = f" element e% mean {d['element_e_pct_mean']:6.2f}" if "element_e_pct_mean" in d else ""
        click.echo(f"{name:24s}{element}{extra}")
    for r in out.get("runs", []):
        wp = r["waypoint_errors"]
        worst = max((abs(w["error_s"]) for w in wp), default=float("nan"))
        click.echo(
            f"run {Path(r['log']).name} @ {r['start_s']:.1f} s ({r['stack']}"
            f"{'' if r['landed'] else ', cut'}): real {r['eta_real_s']:.1f} s, "
            + ", ".join(f"{k} {v:.1f} s" for k, v in r["eta_pred_s"].items())
            + f"; {len(wp)} waypoints, worst arrival error {worst:.1f} s"
        )
    tb = out.get("time_bounds")
    if tb:
        lo, hi = tb["covered_ci95"]
        click.echo(
            f"{tb['coverage']:.0%} time bounds ({tb['source']}): {tb['covered']}/{tb['n_runs']} real runs "
            f"within (Clopper–Pearson 95 %: {lo:.3f}–{hi:.3f})"
        )
    ho = out.get("held_out")
    if ho:
        for key, label in (
            ("leave_one_run_out", "leave-one-run-out"),
            ("leave_one_log_out", "leave-one-log-out"),
        ):
            h = ho[key]
            click.echo(
                f"held out ({label}, chosen among {len(ho['candidates'])} candidates on the other runs): "
                f"run |e%| median {h['run_abs_e_pct_median']:.2f}, worst {h['run_abs_e_pct_worst']:.2f}; "
                f"the prior kept for {h['prior_chosen']}/{len(h['runs'])} runs"
            )
    for row in out.get("table17", []):
        click.echo(
            f"{row['piece']}: t_NN {row['t_nn_s']:.2f} s, t_Real "
            + ", ".join(f"{x:.2f}" for x in row["t_real_s"])
        )


def _evaluate_flights(
    flights: Sequence[str],
    plan: str | None,
    speed: float | None,
    wind_text: str | None,
    segment: float,
    max_gap: float,
    seed: int,
) -> dict[str, Any]:
    """``evaluate FLIGHT…``: every AUTO run predicted by the autopilot's mission execution
    model with the log's own parameters (no training: one flight is enough) beside
    QGroundControl's estimate and plan length ÷ speed; and, where the logs allow, the
    element methods (LVQ, kinematic point mass …) by leave-one-run-out."""
    from uasnav.io.logfile import open_log
    from uasnav.trajectory.flights import flight_samples, leave_one_run_out
    from uasnav.trajectory.mission_runs import MISSION_VIEWS, MODEL, evaluate_logs

    wind = parse_wind(wind_text) if wind_text else None
    # one decoding pass per log serves both evaluations
    opened: list[Any] = [
        open_log(f, need=(*MISSION_VIEWS, "limits"))
        if (Path(f).suffix.lower() in (".tlog", ".bin", ".ulg") and Path(f).is_file()) or Path(f).is_dir()
        else f
        for f in flights
    ]
    table: dict[str, Any] = {}
    mission: dict[str, Any] | None = None
    mission_error = None
    logs_with_plan = [lf for lf in opened if not isinstance(lf, str)]
    if logs_with_plan and plan is None and speed is None:
        try:
            mission = evaluate_logs(logs_with_plan)
            table.update(mission["methods"])
            from uasnav.trajectory.holdout import held_out_report, run_table

            # the model's choices re-made on some runs and scored on the held-out rest
            mission["held_out"] = held_out_report(run_table(logs_with_plan))
        except (InputError, DataFormatError) as e:
            mission_error = str(e)
    element_error: str | None = None
    fs = None
    limits = None
    # warnings (telemetry gaps) are shown once the evaluation succeeded: a failed run prints
    # its one error line only
    with warnings_after_success():
        try:
            # the element methods measure elements between waypoints the telemetry names:
            # logs without them (PX4 keeps its mission out of the telemetry) are left to the
            # mission model when it evaluates them
            element_logs = [
                lf
                for lf in opened
                if isinstance(lf, str) or plan is not None or mission is None or lf.flight.waypoints
            ]
            skipped = [Path(str(lf.path)).name for lf in opened if lf not in element_logs]
            if skipped:
                element_error = f"{', '.join(skipped)}: no waypoints in the telemetry"
            if not element_logs:
                raise InputError(element_error or "no flights")
            fs = flight_samples(element_logs, plan, speed, wind, segment, max_gap)
            limits, _ = _log_limits(flights, fs.logs)
            errors = leave_one_run_out(fs, segment, random_state=seed, accel_ms2=limits.accel_ms2 or 1.0)
        except InputError as why:
            if mission is None:
                if mission_error is not None and mission_error != str(why):
                    # neither evaluation applies: say why for both
                    raise InputError(f"mission model: {mission_error}; element methods: {why}") from why
                raise
            element_error = "; ".join(dict.fromkeys(x for x in (element_error, str(why)) if x))
            errors, fs = [], None
    for res in errors:
        table[res.name] = (
            {
                "applicable": True,
                "element_e_pct_mean": float(np.mean(res.element_pct)),
                "element_e_pct_median": float(np.median(res.element_pct)),
                "run_e_pct_mean": float(np.mean(res.run_pct)),
                # per-run ETA error |e%|: median, 95th percentile, worst
                "run_abs_e_pct_median": float(np.median(np.abs(res.run_pct))),
                "run_abs_e_pct_p95": float(np.percentile(np.abs(res.run_pct), 95)),
                "run_abs_e_pct_worst": float(np.max(np.abs(res.run_pct))),
                "run_e_pct": list(res.run_pct),
            }
            if res.applicable
            else {"applicable": False, "reason": res.reason}
        )
    from uasnav.trajectory.models import DEFAULT_METHOD

    out: dict[str, Any] = {
        "methods": table,
        # the mission execution model when the logs carry their missions; else the element
        # method `train` fits by default (chosen by leave-one-run-out)
        "default_method": MODEL
        if mission is not None
        else {"kinematic": "kinematic point mass", "lvq": "LVQ (thesis)"}[DEFAULT_METHOD],
        "n_runs": len(fs) if fs is not None else len(mission["runs"]) if mission else 0,
        "n_elements": fs.n_elements if fs is not None else 0,
    }
    if limits is not None:
        # the kinematic models' limits: from the logs' parameters, else the stated defaults
        out["limits"] = {"accel_ms2": limits.accel_ms2, "from_log": "accel_ms2" in limits.source}
    if mission is not None:
        out["runs"] = mission["runs"]
        out["per_stack"] = mission["per_stack"]
        out["parameters"] = mission["parameters"]
        out["time_bounds"] = mission["time_bounds"]
        out["held_out"] = mission["held_out"]
    if element_error is not None:
        out["element_methods"] = f"not evaluated: {element_error}"
    if mission_error is not None:
        out["mission_model"] = f"not evaluated: {mission_error}"
    return out


@command.command("mission")
@click.argument("plan_path", metavar="PLAN", type=click.Path(dir_okay=False))
@click.option(
    "--autopilot",
    type=click.Choice(["arducopter", "px4-mc", "plane"]),
    help="Autopilot family that flies the plan; default the log's (--params-from), else from the "
    "plan (fixed-wing/VTOL commands: plane), else arducopter.",
)
@click.option("--firmware", help="Firmware version (e.g. 3.6, 4.5, 1.14); default the log's or current.")
@click.option(
    "--params-from",
    "params_log",
    type=click.Path(dir_okay=False),
    help="Flight log (.tlog .bin .ulg) of the vehicle: its parameters replace the firmware defaults.",
)
@click.option("--home-alt", type=Real(-1000.0, 9000.0), help="Home altitude AMSL (m) for AMSL items.")
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
def mission(plan_path, autopilot, firmware, params_log, home_alt, as_json):  # type: ignore[no-untyped-def]
    """When each item of PLAN (.plan, .waypoints, a log's mission) is reached and when the
    mission ends, as the autopilot flies it (no training: the firmware's mission execution with
    the vehicle's parameters or the firmware defaults, each with its source), beside
    QGroundControl's own mission-time estimate."""
    from uasnav.io.plans import read_plan
    from uasnav.trajectory.autopilot import (
        family_of,
        mission_params,
        plan_family,
        predict_mission,
        qgc_mission_time,
    )

    plan = read_plan(plan_path)
    log_params: dict[str, float] = {}
    ident = None
    if params_log:
        from uasnav.io.logfile import open_log

        lf = open_log(params_log, need=("params", "identity"))
        log_params, ident = lf.params, lf.identity
    if autopilot is None:
        if ident is not None:
            autopilot = family_of(ident, log_params)
        else:
            autopilot = plan_family(plan)
    version = firmware or (getattr(ident, "firmware_version", None) if ident is not None else None)
    params = mission_params(autopilot, version, log_params)
    pred = predict_mission(plan, params, home_amsl_m=home_alt)
    qgc = qgc_mission_time(plan, params.cruise_ms, home_alt)
    out = {
        "autopilot": autopilot,
        "firmware": params.version,
        "eta_s": pred.eta_s,
        "landed": pred.landed,
        "qgc_estimate_s": qgc,
        "items": [
            {"item": int(i), "command": int(c), "arrive_s": float(t)}
            for i, c, t in zip(pred.items, pred.commands, pred.arrive_s, strict=True)
        ],
        "parameters": {k: {"value": params.values[k], "source": params.sources[k]} for k in params.values},
    }
    if as_json:
        echo_json(out)
        return
    for r in out["items"]:
        click.echo(f"item {r['item']:>3} (MAV_CMD {r['command']:>3}) reached at {r['arrive_s']:8.1f} s")
    end = "touch-down" if pred.landed else "last item"
    click.echo(
        f"ETA ({end}) {pred.eta_s:.1f} s, {autopilot} {params.version or ''}".rstrip()
        + f"; QGroundControl's estimate {qgc:.1f} s"
    )
    from_log = sorted(k for k, v in params.sources.items() if v == "log")
    click.echo(f"parameters from the log: {', '.join(from_log) or 'none'}; others the firmware defaults")


def _flights_option(what: str):  # type: ignore[no-untyped-def]
    """``--flights LOG`` (repeatable): the vehicle's own earlier flights, for ``what``."""
    return click.option(
        "--flights",
        "flight_logs",
        multiple=True,
        type=click.Path(dir_okay=False),
        help="The vehicle's own earlier flights (.tlog .bin .ulg with their mission; repeat the option): "
        + what,
    )


@command.command("calibrate")
@click.option(
    "--model", "model_path", required=True, type=click.Path(dir_okay=False), help="Model JSON (from train)."
)
@click.option(
    "--out", "out", required=True, type=OutputPath(), help="Model JSON to write, with its time bounds."
)
@click.option(
    "--runs",
    type=click.IntRange(20, 100_000),
    default=200,
    show_default=True,
    help="Simulated calibration runs.",
)
@click.option(
    "--test-runs",
    type=click.IntRange(0, 100_000),
    default=0,
    show_default=True,
    help="Held-out simulated runs to report the coverage on.",
)
@click.option(
    "--coverage",
    type=PROBABILITY,
    default=0.95,
    show_default=True,
    help="Coverage reported for the held-out runs.",
)
@_flights_option("the bounds come from their AUTO runs instead of simulation.")
@click.option("--seed", type=SEED, default=0, show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
def calibrate(model_path, out, runs, test_runs, coverage, flight_logs, seed, as_json):  # type: ignore[no-untyped-def]
    """Calibrate the time bounds of a model: split-conformal on the vehicle's own earlier
    flights (--flights: each AUTO run scored at its waypoint arrivals and its end, predicted by
    the autopilot's mission execution model), else on simulated 3D runs with truth (random
    routes with take-off, sloped legs, holds and landing, scored at every element). The source
    is kept in the model and stated in the intents made with it."""
    if flight_logs:
        _calibrate_from_flights(model_path, out, flight_logs, coverage, as_json)
        return
    from uasnav.trajectory.calibration import calibrate as fit_bounds
    from uasnav.trajectory.calibration import check_runs, covered
    from uasnav.trajectory.calibration import simulated_route_runs as simulated_runs
    from uasnav.trajectory.models import load_model, method_of
    from uasnav.trajectory.timebounds import clopper_pearson

    check_runs(runs + test_runs, "--runs + --test-runs")
    check_outputs([model_path], {"--out": out})
    model = load_model(model_path)
    with click.progressbar(length=runs + test_runs, label="simulated runs", file=sys.stderr) as bar:
        cal = simulated_runs(model, runs, seed=2 * seed, progress=lambda i, n: bar.update(1))
        test = simulated_runs(model, test_runs, seed=2 * seed + 1, progress=lambda i, n: bar.update(1))
    model.time_bounds_ = fit_bounds(cal, source=f"{runs} simulated runs, seed {seed}")
    q = model.time_bounds_.quantile(coverage)
    res = {
        "method": method_of(model),
        "runs": runs,
        "coverage": coverage,
        "quantile": q,
        "tau_s": model.time_bounds_.tau_s,
    }
    if test_runs:
        k = sum(covered(model.time_bounds_, r, coverage) for r in test)
        lo, hi = clopper_pearson(k, test_runs)
        res |= {"test_runs": test_runs, "covered": k, "covered_ci95": [lo, hi]}
    model.save(out)
    if as_json:
        echo_json(res)
        return
    click.echo(
        f"{res['method']} model, time bounds: ±{q:.3f}·(t + {model.time_bounds_.tau_s:g} s) at "
        f"{coverage:.0%} coverage, {runs} runs"
    )
    if test_runs:
        click.echo(
            f"held-out coverage {res['covered']}/{test_runs} (Clopper–Pearson 95 %: {lo:.3f}–{hi:.3f})"
        )


def _calibrate_from_flights(
    model_path: str, out: str, flight_logs: Sequence[str], coverage: float, as_json: bool
) -> None:
    """``calibrate --flights``: the model's time bounds from the vehicle's own AUTO runs."""
    from uasnav.trajectory.mission_runs import calibrate_from_flights
    from uasnav.trajectory.models import load_model, method_of

    check_outputs([model_path, *flight_logs], {"--out": out})
    model = load_model(model_path)
    bounds = calibrate_from_flights(flight_logs)
    q = bounds.quantile(coverage)  # refuses a coverage that too few runs cannot give
    model.time_bounds_ = bounds
    model.save(out)
    res = {
        "method": method_of(model),
        "runs": bounds.n_runs,
        "coverage": coverage,
        "quantile": q,
        "tau_s": bounds.tau_s,
        "source": bounds.source,
    }
    if as_json:
        echo_json(res)
        return
    click.echo(
        f"{res['method']} model, time bounds: ±{q:.3f}·(t + {bounds.tau_s:g} s) at {coverage:.0%} "
        f"coverage from {bounds.source}"
    )


def _own_run_bounds(
    model: Any,
    flight_logs: Sequence[str],
    limits_log: Any,
    coverage: float,
    wind: np.ndarray,
    climb: float | None,
    descent: float | None,
    accel_z: float | None,
    speed: float | None,
) -> str:
    """``intent``: the time bounds from the vehicle's own AUTO runs (``--flights``, else the
    ``--limits-from`` log's when it has enough runs for the coverage) set on ``model``; returns
    why they were not used (to append to the simulated bounds' source), or "". Explicit
    ``--flights`` that cannot give the coverage are an error."""
    from uasnav.trajectory.timebounds import DEFAULT_TAU_S
    from uasnav.utm.intent import vehicle_run_bounds

    logs = list(flight_logs) or ([limits_log] if limits_log else [])
    if not logs:
        return ""
    prior = model.time_bounds_
    tau = prior.tau_s if prior is not None else DEFAULT_TAU_S
    try:
        bounds = vehicle_run_bounds(
            logs, model, wind, climb_ms=climb, descent_ms=descent, accel_z_ms2=accel_z, cruise_ms=speed,
            tau_s=tau,
        )  # fmt: skip
        bounds.quantile(coverage)
    except (InputError, DataFormatError) as why:
        if flight_logs:
            raise InputError(f"--flights: {why}") from why
        name = Path(str(getattr(logs[0], "path", logs[0]))).name
        return f" (the vehicle's own runs in {name} not used: {why})"
    model.time_bounds_ = bounds
    return ""


@command.command("intent")
@click.option(
    "--model",
    "model_path",
    required=True,
    type=click.Path(dir_okay=False),
    help="Model JSON (from train/calibrate).",
)
@click.option(
    "--plan",
    "plan_path",
    required=True,
    type=click.Path(dir_okay=False),
    help="Plan: .plan, .waypoints, .csv.",
)
@click.option("--wind", "wind_text", required=True, help="SPEED@DIR: m/s @ degrees the wind comes from.")
@click.option(
    "--start",
    "start_text",
    required=True,
    help="Departure time, ISO 8601 with a zone (2026-05-01T09:30:00Z).",
)
@click.option(
    "--coverage", type=PROBABILITY, default=0.95, show_default=True, help="Coverage of the time bounds."
)
@click.option(
    "--lateral-buffer",
    type=Real(0.0, 1e5, lo_open=True),
    default=15.0,
    show_default=True,
    help="Horizontal buffer around the path (m, at most 100 km).",
)
@click.option(
    "--vertical-buffer", type=BUFFER_M, default=10.0, show_default=True, help="Vertical buffer (m)."
)
@click.option(
    "--geoid-height",
    type=Real(-120.0, 120.0),
    help="Geoid height N at the site (m; W84 = AMSL + N). Default: the EGM96 geoid at each route "
    "point (NGA's 15′ grid, shipped with uasnav).",
)
@click.option("--home-alt", type=Real(-1000.0, 9000.0), help="Home altitude AMSL (m) if the plan has none.")
@click.option("--speed", type=UAS_SPEED, help="Horizontal speed (m/s); default the plan's, else the model's.")
@click.option(
    "--climb-rate",
    type=UAS_SPEED,
    help="Climb speed (m/s); default a kinematic model's own limit, else ArduPilot's 2.5.",
)
@click.option(
    "--descent-rate",
    type=UAS_SPEED,
    help="Descent speed (m/s); default a kinematic model's own limit, else ArduPilot's 1.5.",
)
@click.option(
    "--limits-from",
    "limits_log",
    type=click.Path(dir_okay=False),
    help="Flight log (.tlog .bin .ulg) of the vehicle: its WPNAV_SPEED_UP/DN, WPNAV_ACCEL_Z or "
    "MPC_Z_V_AUTO_UP/DN (MPC_Z_VEL_MAX_UP/DN before PX4 1.12), MPC_ACC_UP_MAX replace the model's "
    "vertical limits, its WPNAV_SPEED or "
    "MPC_XY_CRUISE the model's speed (explicit options and the plan's own speed win).",
)
@click.option(
    "--priority", type=click.IntRange(0, 2**31 - 1), default=0, show_default=True, help="F3548 priority."
)
@click.option(
    "--calibration-runs",
    type=click.IntRange(20, 100_000),
    default=200,
    show_default=True,
    help="Runs to calibrate a model without time bounds.",
)
@_flights_option(
    "the time bounds come from how this prediction missed their AUTO runs. Default: the "
    "--limits-from log's runs when there are enough for --coverage, else the model's bounds."
)
@click.option(
    "--out", "out", required=True, type=OutputPath(), help="F3548 OperationalIntentDetails JSON to write."
)
@click.option("--geojson", "geojson", type=OutputPath(), help="Also write the volumes and route as GeoJSON.")
@click.option("--json", "as_json", is_flag=True, help="Print a machine-readable summary.")
def intent(  # type: ignore[no-untyped-def]
    model_path, plan_path, wind_text, start_text, coverage, lateral_buffer, vertical_buffer, geoid_height,
    home_alt, speed, climb_rate, descent_rate, limits_log, priority, calibration_runs, flight_logs, out,
    geojson, as_json,
):  # fmt: skip
    """An ASTM F3548 operational intent (W84 volumes) whose volumes contain the predicted 4D
    trajectory with its calibrated time bounds and the buffers."""
    from uasnav.cli.utm import parse_time
    from uasnav.geo import frames
    from uasnav.io.operational_intent import write_intent, write_intent_geojson
    from uasnav.io.plans import plan_cruise_speed, read_plan
    from uasnav.trajectory.calibration import calibrate as fit_bounds
    from uasnav.trajectory.calibration import simulated_route_runs as simulated_runs
    from uasnav.trajectory.models import load_model, method_of
    from uasnav.trajectory.route3d import check_holds, vertical_limits
    from uasnav.utm.altitude import geoid_model
    from uasnav.utm.intent import build_intent

    wind = parse_wind(wind_text)
    start = parse_time(start_text, "--start")
    check_outputs([model_path, plan_path, *flight_logs], {"--out": out, "--geojson": geojson})
    model = load_model(model_path)
    plan = read_plan(plan_path)
    check_holds(plan)  # before the calibration runs: a plan that cannot be timed fails at once
    # vertical limits: the explicit options, else the log's (--limits-from), else the model's
    # own (build_intent → route3d.vertical_limits)
    accel_z: float | None = None
    from_log: list[str] = []
    limits_source: Any = limits_log
    if limits_log:
        from uasnav.io.autopilot_limits import read_autopilot_limits

        if Path(limits_log).suffix.lower() in (".tlog", ".bin", ".ulg"):
            from uasnav.io.logfile import open_log
            from uasnav.trajectory.mission_runs import MISSION_VIEWS

            # one decoding pass serves the limits and the vehicle's own runs
            limits_source = open_log(limits_log, need=("limits", *MISSION_VIEWS))
            lim = limits_source.limits
        else:
            lim = read_autopilot_limits(limits_log)
        if lim.climb_ms is not None and climb_rate is None:
            climb_rate, from_log = lim.climb_ms, [*from_log, "climb_ms"]
        if lim.descent_ms is not None and descent_rate is None:
            descent_rate, from_log = lim.descent_ms, [*from_log, "descent_ms"]
        if lim.accel_z_ms2 is not None:
            accel_z, from_log = lim.accel_z_ms2, [*from_log, "accel_z_ms2"]
        if lim.cruise_ms is not None and speed is None and plan_cruise_speed(plan) is None:
            speed, from_log = lim.cruise_ms, [*from_log, "cruise_ms"]
        found = [
            k for k in ("climb_ms", "descent_ms", "accel_z_ms2", "cruise_ms") if getattr(lim, k) is not None
        ]
        if not found:
            raise InputError(
                f"--limits-from {limits_log}: no vehicle limits in this log (empty, corrupt, or without "
                "autopilot parameters); give --climb-rate/--descent-rate/--speed or another log"
            )
        explicit = {"climb_ms": climb_rate, "descent_ms": descent_rate, "cruise_ms": speed}
        defaulted = [
            k for k in ("climb_ms", "descent_ms", "accel_z_ms2") if k not in found and explicit.get(k) is None
        ]
        if defaulted:
            warnings.warn(
                f"--limits-from {limits_log}: {', '.join(defaulted)} not in the log's parameters; "
                "the model's defaults are used for them",
                stacklevel=1,
            )
    own_note = _own_run_bounds(
        model, flight_logs, limits_source, coverage, wind, climb_rate, descent_rate, accel_z, speed
    )
    if model.time_bounds_ is None:
        from uasnav.trajectory.calibration import check_runs

        check_runs(calibration_runs, "--calibration-runs")
        with click.progressbar(
            length=calibration_runs, label="calibrating time bounds", file=sys.stderr
        ) as bar:
            # calibrated at the speed this mission flies (the band depends on it)
            v = speed or plan_cruise_speed(plan) or model.cruise_ms_
            runs = simulated_runs(model, calibration_runs, progress=lambda i, n: bar.update(1), cruise_ms=v)
        model.time_bounds_ = fit_bounds(
            runs, source=f"{calibration_runs} simulated runs at {v:g} m/s, seed 0{own_note}"
        )
    b = build_intent(
        plan, model, wind, start, coverage=coverage, lateral_buffer_m=lateral_buffer,
        vertical_buffer_m=vertical_buffer, geoid_height_m=geoid_height, home_amsl_m=home_alt,
        climb_ms=climb_rate, descent_ms=descent_rate, accel_z_ms2=accel_z, cruise_ms=speed,
        priority=priority,
    )  # fmt: skip
    up, down, a_z = vertical_limits(model, climb_rate, descent_rate, accel_z)
    write_intent(b.details, out)
    if geojson:
        la, lo, _ = frames.enu_to_geodetic(
            b.route_en[:, 0], b.route_en[:, 1], 0.0, b.origin[0], b.origin[1], 0.0
        )
        write_intent_geojson(
            b.details,
            geojson,
            [(float(x), float(y), float(z)) for x, y, z in zip(la, lo, b.route_alt_w84, strict=True)],
        )
    summary = {
        "method": method_of(model),
        "volumes": len(b.details.volumes),
        "eta_s": b.eta_s,
        "eta_bounds_s": list(b.eta_bounds_s),
        "coverage": coverage,
        "waypoint_times_s": b.t_arrive_s,
        "waypoint_bounds_s": [[float(x), float(y)] for x, y in zip(b.t_lo_s, b.t_hi_s, strict=True)],
        "low_confidence_elements": sum(bool(f) for f in b.flags),
        "climb_ms": up,
        "descent_ms": down,
        "accel_z_ms2": a_z,
        "limits_from_log": from_log,
        # what calibrated the time bounds: the vehicle's own flights or simulation
        "time_bounds_source": b.time_bounds_source,
        # where the W84 altitudes' geoid heights came from: the user's N, or the installed model
        "geoid": "given" if geoid_height is not None else geoid_model(),
    }
    if b.route_prediction is not None:
        el = b.route_prediction.elements
        # the 3D elements by kind: how many, and their predicted time (s)
        summary["elements"] = {
            str(k): {"count": int((el.kind == k).sum()), "time_s": float(el.time_s[el.kind == k].sum())}
            for k in ("leg", "turn", "climb", "descent", "hover")
        }
    if as_json:
        echo_json(summary)
        return
    click.echo(
        f"{len(b.details.volumes)} volumes; ETA {b.eta_s:.0f} s "
        f"({b.eta_bounds_s[0]:.0f}–{b.eta_bounds_s[1]:.0f} s at {coverage:.0%}, bounds from "
        f"{b.time_bounds_source or 'calibration'}); wrote {out}"
    )
