"""The audit command: the grid abstraction against traffic and sensing that do not keep to it."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import click
from rich.table import Table

from ci.cli.common import (
    err,
    faults_options,
    overtaken_option,
    print_header,
    print_json,
    print_paths,
    print_table,
    vehicle_speeds_option,
)
from ci.shared.executors import ExecutorChoice, ExecutorKind, check_executor
from ci.shared.options import (
    CELL_M,
    FRACTION,
    KM,
    METRES,
    PER_HOUR,
    PER_RUN,
    RUNS,
    SCALE,
    SCHEDULER,
    SEED,
    WORKERS,
    convert,
    names,
)
from ci.shared.options import out_dir as out_dir_checked
from ci.shared.records import campaign_lock
from spec.dynamics import Overtaken, VehicleSpeeds
from spec.errors import ExitCode, OptionError
from spec.escapes import Semantics, parse_semantics
from spec.grid import STANDARD_CELLS_M, grid_for
from spec.physical import EVENTS, NOISE


def _models(option: str, text: str, known: dict[str, Any]) -> tuple[str, ...]:
    """Distinct registered model names."""
    from sim.parts import check_name

    return names(option, text, lambda name: check_name(option, name, known))


def _semantics(text: str | None, models: tuple[str, ...]) -> tuple[Semantics, ...]:
    """Distinct semantics of the sound model (``spec.escapes.Semantics``; None: the loop's own), given only when the
    sound model is audited."""
    from sim.parts import loop_semantics

    if text is None:
        return (loop_semantics("sound"),)
    if "sound" not in models:
        raise OptionError("--semantics", text, "needs the sound model among --model (the paper's rules plan whole "
                          "plans)")
    return tuple(parse_semantics(word, "--semantics") for word in names("--semantics", text))


def _scales(text: str) -> tuple[float, ...]:
    """Distinct bound-width factors (``spec.assumptions.world_bounds``), each finite and at least 0."""
    scales = tuple(convert("--bounds-scale", SCALE, word) for word in names("--bounds-scale", text))
    if len(set(scales)) < len(scales):
        raise OptionError("--bounds-scale", text, "a factor given twice")
    return scales


def parse_cells(text: str) -> tuple[float, ...]:
    """The ``--cells`` list: usable cell lengths, none twice; else bad input naming the list."""
    cells = []
    for word in names("--cells", text):
        value = convert("--cells", CELL_M, word)
        try:
            grid_for(value)
        except OptionError as error:  # it names --cell-m: say which list the length came from
            raise OptionError("--cells", word, f"not a usable --cell-m: {error.reason}") from None
        cells.append(value)
    if len(set(cells)) < len(cells):
        raise OptionError("--cells", text, "a cell length given twice")
    return tuple(cells)


@click.command()
@click.option("--cells", default=",".join(f"{float(c):g}" for c in STANDARD_CELLS_M), show_default=True,
              help="Cell lengths in metres, comma-separated.")
@click.option("--traffic", "traffic_text", default="paper,spread,following", show_default=True)
@click.option("--sensing", "sensing_text", default="exact,noisy", show_default=True)
@click.option("--model", "model_text", default="paper,sound", show_default=True,
              help="The models that plan, compared over the same seeds: paper (its rules), sound (under the world's "
                   "bounds, spec.assumptions.world_bounds).")
@click.option("--semantics", "semantics_text", default=None,
              help="How the sound model decides, comma-separated, each a combination of its own: commit (a committed "
                   "part with a proved escape, the default) or whole (plans proved to their end); "
                   "docs/closed-loop.md.")
@click.option("--bounds-scale", "scale_text", default="1", show_default=True,
              help="Factors on the world's bounds' widths (speeds about their middle, the sensing error), "
                   "comma-separated: 1 is the rule's own bounds. Every drive's containment is measured against them.")
@click.option("--km", type=KM, default=25.0, show_default=True,
              help="Kilometres per run (a collision does not end a run: it starts again where it stands).")
@click.option("--runs", type=RUNS, default=4, show_default=True, help="Seeds per combination.")
@click.option("--seed", type=SEED, default=1, show_default=True, help="Run i uses seed + i.")
@click.option("--engine", default="interpreter", show_default=True, help="The planner in the loop.")
@click.option("--engines", "cost_engines", default="interpreter,spin,z3", show_default=True,
              help="Engines whose planning cost is measured on the scenarios the planner saw.")
@click.option("--snapshots", type=PER_RUN, default=20, show_default=True,
              help="Scenarios kept per run for the planning cost.")
@click.option("--opportunity-checks", type=PER_RUN, default=50, show_default=True,
              help="Decisions without an overtake replayed in physics per run, at most (a 1 in 4 sample).")
@click.option("--stop-rate-per-h", type=PER_HOUR, default=EVENTS.stop_rate_per_h, show_default=True,
              help="Left-lane vehicles braking to a standstill, per vehicle-hour (spread, following).")
@click.option("--min-spawn-gap-m", type=METRES, default=EVENTS.min_spawn_gap_m, show_default=True,
              help="Smallest bumper-to-bumper spawn gap (spread, following).")
@click.option("--range-sd-m", type=METRES, default=NOISE.range_sd_m, show_default=True,
              help="Range noise of the noisy sensor (standard deviation).")
@click.option("--miss-rate", type=FRACTION, default=NOISE.miss_rate, show_default=True,
              help="Missed detections of the noisy sensor, per reading.")
@click.option("--workers", type=WORKERS, default=2, show_default=True)
@click.option("--executor", "executor_kind", type=click.Choice([k.value for k in ExecutorKind]),
              default=ExecutorKind.PROCESSES.value, show_default=True)
@click.option("--scheduler", type=SCHEDULER, default=None, help="With --executor dask: a running scheduler's address.")
@click.option("--out", "out_dir", default="out/audit", show_default=True,
              help="audit.jsonl (resumable), audit.json, audit.md and plots.")
@click.option("--fresh", is_flag=True, help="Forget the runs already recorded in --out instead of resuming.")
@faults_options
@vehicle_speeds_option
@overtaken_option
@click.option("--json", "as_json", is_flag=True)
def audit(cells: str, traffic_text: str, sensing_text: str, model_text: str, semantics_text: str | None,
          scale_text: str, km: float, runs: int,
          seed: int, engine: str,
          cost_engines: str, snapshots: int, opportunity_checks: int, stop_rate_per_h: float,
          min_spawn_gap_m: float, range_sd_m: float, miss_rate: float, workers: int, executor_kind: str,
          scheduler: str | None, out_dir: str, fresh: bool, faults: str, steering_offset_deg: float,
          tracking: bool, vehicle_speeds: VehicleSpeeds, overtaken: Overtaken, as_json: bool) -> None:
    """Audit the grid abstraction: cell size x traffic model x sensing model x seeds, driven closed-loop."""
    from ci.audit.campaign import (
        AuditPlan,
        decider,
        figure,
        label,
        moves,
        planning_cost,
        rows,
        run_audit,
        write_reports,
    )
    from ci.shared.progress import km_progress
    from sim.parts import PLANNING_MODELS, SENSOR_MODELS, TRAFFIC_MODELS, DriveConfig
    from spec.engines import get_engine

    executor = ExecutorChoice(ExecutorKind(executor_kind), workers, scheduler)
    check_executor(executor)
    out_dir_checked("--out", out_dir)
    click.get_current_context().with_resource(campaign_lock(Path(out_dir)))  # before any line: one campaign per folder
    engines = names("--engines", cost_engines, lambda name: get_engine(name).ready())  # installed, or exit 4
    base = DriveConfig(km, engine=engine, stop_rate_per_h=stop_rate_per_h, min_spawn_gap_m=min_spawn_gap_m,
                       range_sd_m=range_sd_m, miss_rate=miss_rate, snapshots=snapshots, restart_after_collision=True,
                       opportunity_checks=opportunity_checks, faults=faults,
                       steering_offset_deg=steering_offset_deg, tracking=tracking, vehicle_speeds=vehicle_speeds,
                       overtaken=overtaken)
    deciding = _models("--model", model_text, dict(PLANNING_MODELS))
    plan = AuditPlan(parse_cells(cells), _models("--traffic", traffic_text, dict(TRAFFIC_MODELS)),
                     _models("--sensing", sensing_text, dict(SENSOR_MODELS)), tuple(range(seed, seed + runs)), base,
                     deciding, _scales(scale_text), _semantics(semantics_text, deciding))
    configs = plan.configs()
    for config in configs:
        config.parts()  # the engine exists and answers each model: bad input before any run starts
    get_engine(engine).ready()  # its tools are installed (exit 4), or every plan of every run would fail
    total = len(configs) * runs
    print_header(err, f"audit: {len(configs)} combination(s) x seeds {seed}..{seed + runs - 1} = {total} run(s) of "
                 f"{km:g} km; planner {engine}; faults {base.faults or 'none'}; "
                 f"tracking {'on' if tracking else 'off'}; on {executor.describe(total)}", out_dir)
    labels = {i: f"{c.cell_m:g} m, {c.traffic}, {c.sensor}, {decider(c.model, c.decides.value)}"
                 + ("" if c.bounds_scale == 1 else f" x{c.bounds_scale:g}") + f", seed {s}"
             for i, (c, s) in enumerate((c, s) for c in configs for s in plan.seeds)}
    with km_progress(err, total, km, "already in audit.jsonl (resumed; --fresh runs it again)") as bar:
        results = run_audit(plan, out_dir, executor, fresh,
                            lambda i, done, resumed: bar.done(done.summary, resumed, i, labels[i]), bar.moved)
    err.print("audit: planning cost on the scenarios the planner saw ...")
    audit_rows, costs = rows(results), planning_cost(results, engines)
    paths = write_reports(audit_rows, costs, plan, out_dir)
    if as_json:
        print_json({"combinations": [r.to_json() for r in audit_rows], "planning_cost": [c.to_json() for c in costs]})
    else:
        table = Table(title="the grid abstraction against traffic and sensing that do not keep to it")
        for col in ("cell m", "traffic", "sensing", "model", "km", "collisions /1000 km", "near misses /1000 km",
                    "not started: succeeded (checked)", "missed /1000 km est.", "delayed /1000 km est.",
                    "traffic collisions", "min gap ahead m", "violations",
                    "plan ms"):
            table.add_column(col, justify="right")
        for r in audit_rows:
            table.add_row(f"{r.cell_m:g}", r.traffic, r.sensing, label(r), f"{r.km:.1f}",
                          f"{r.collisions} ({figure(r.collisions_per_1000_km)})",
                          f"{r.near_misses} ({figure(r.near_misses_per_1000_km)})",
                          f"{r.opportunity_total('missed')} ({r.opportunity_total('checked')})",
                          figure(r.missed_per_1000_km), figure(r.delayed_per_1000_km), str(r.traffic_collisions),
                          figure(r.min_gap_left_m, 2), str(r.violations), figure(r.plan_ms_median, 2))
        print_table(table, 4, "audit.md and audit.json")
        models = Table(title="the models side by side: safety inside / after the assumptions, containment, price")
        for col in ("cell m", "traffic", "sensing", "model", "overtakes /km", "collisions in / after /1000 km",
                    "near misses in / after /1000 km", "breaches /1000 km", "re-plans on a breach",
                    "moves finished, undone, sent back", "keep-lane",
                    "minimal-risk", "take-overs (after breach)", "waits without plan", "unsafe starts"):
            models.add_column(col, justify="right")
        for r in audit_rows:
            models.add_row(f"{r.cell_m:g}", r.traffic, r.sensing, label(r),
                           figure(r.per_1000_km(r.overtakes) / 1000, 2),
                           r.inside_after("contact"), r.inside_after("near_miss"),
                           figure(r.per_1000_km(sum(r.breaches.values()))), str(r.breach_replans),
                           moves(r), str(r.keep_lane_steps), str(r.minimal_risk_steps),
                           f"{r.takeovers} ({r.takeovers_after_breach})", str(r.waits_without_plan),
                           str(r.unsafe_starts))
        print_table(models, 4, "audit.md and audit.json")
        kinds = sorted({k for r in audit_rows for k in r.faults if k != "none"})
        if kinds:
            faults_table = Table(title="faults: started / sweeps changed / failures attributed")
            for col in ("cell m", "traffic", "sensing", "model", *kinds, "no fault", "lost control", "unreadable"):
                faults_table.add_column(col, justify="right")
            for r in audit_rows:
                faults_table.add_row(f"{r.cell_m:g}", r.traffic, r.sensing, label(r), *(r.fault_cell(k) for k in kinds),
                                     str(r.faults.get("none", {}).get("failures", 0)), str(r.losses_of_control),
                                     str(r.unreadable))
            print_table(faults_table, 4, "audit.md and audit.json")
        cost_table = Table(title="planning cost on the scenarios the planner saw (shortest)")
        for col in ("cell m", "model", "engine", "n", "median ms", "p99 ms", "median states", "incomplete"):
            cost_table.add_column(col, justify="right")
        for c in costs:
            cost_table.add_row(f"{c.cell_m:g}", c.model, c.engine, str(c.n), figure(c.median_ms, 2),
                               figure(c.p99_ms, 2), figure(c.median_states, 0), str(c.incomplete))
        print_table(cost_table, 3, "audit.md and audit.json")
        print_paths("written:", paths)
    sys.exit(ExitCode.OK)


COMMANDS = (audit,)
