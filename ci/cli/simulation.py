"""The closed-loop command: drive the PyBullet simulator, a campaign of seeds, resumable."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from ci.cli.common import (
    err,
    faults_options,
    loop_semantics_option,
    overtaken_option,
    print_header,
    print_json,
    print_table,
    strategy_option,
    vehicle_speeds_option,
)
from ci.shared.executors import ExecutorChoice, ExecutorKind, check_executor
from ci.shared.options import CELL_M, KM, RUNS, SCHEDULER, SEED, TOLERANCE, WORKERS
from ci.shared.options import out_dir as out_dir_checked
from ci.shared.records import campaign_lock
from spec.answers import Strategy
from spec.dynamics import Overtaken, VehicleSpeeds
from spec.engines import get_engine
from spec.errors import ExitCode, OptionError
from spec.escapes import Semantics
from spec.grid import PAPER_GRID
from spec.physical import LOOP


@click.command()
@click.option("--km", type=KM, default=5.0, show_default=True,
              help="Kilometres per run (with --until-failure: the cap).")
@click.option("--until-failure", is_flag=True,
              help="Stop each run at its first failure, a collision or a loss of control (capped by --km); a "
                   "snapshot that could not be read and a wait without a plan are counted apart.")
@click.option("--until-sensing-failure", is_flag=True,
              help="Stop each run at its first failure a sensing fault caused (capped by --km); after any other "
                   "failure (a steering fault's loss of control, a collision no sensing fault touched) the drive "
                   "starts again where it stands and the failure is counted apart: km between sensing-caused "
                   "failures, as the reliability target counts them.")
@click.option("--seed", type=SEED, default=1, show_default=True, help="Run i uses seed + i.")
@click.option("--engine", default="interpreter", show_default=True)
@strategy_option(choices=(Strategy.SENSIBLE, Strategy.SHORTEST))
@click.option("--cell-m", "cell_m", type=CELL_M, default=PAPER_GRID.cell, show_default=True,
              help="The planner's cell length in metres (21, 10.5, 7, 5.25); the world stays the paper's.")
@click.option("--model", default="paper", show_default=True,
              help="The model that plans: paper (its rules) or sound (under the world's bounds, "
                   "spec.assumptions.world_bounds; containment is measured under both).")
@click.option("--runs", type=RUNS, default=1, show_default=True)
@click.option("--workers", type=WORKERS, default=1, show_default=True,
              help="Local processes (with --executor dask and no --scheduler: the local cluster's workers).")
@click.option("--executor", "executor_kind", type=click.Choice([k.value for k in ExecutorKind]),
              default=ExecutorKind.PROCESSES.value, show_default=True,
              help="Where runs go: local processes or a dask.distributed cluster.")
@click.option("--scheduler", type=SCHEDULER, default=None, help="With --executor dask: a running scheduler's address.")
@click.option("--out", "out_dir", default="out/sim", show_default=True,
              help="Runs (runs.jsonl, resumable), traces (JSON lines) and plots.")
@click.option("--fresh", is_flag=True, help="Forget the runs already recorded in --out instead of resuming.")
@click.option("--step-tolerance", type=TOLERANCE, default=LOOP.step_tolerance_cells,
              show_default=True, help="Cells one action may add to a vehicle's deviation from the prediction.")
@click.option("--plan-tolerance", type=TOLERANCE, default=LOOP.plan_tolerance_cells,
              show_default=True, help="Cells a vehicle may deviate over a plan.")
@click.option("--paper-replanning", is_flag=True,
              help="Re-plan only as the paper did (not when a deviation exceeds the tolerance).")
@faults_options
@vehicle_speeds_option
@overtaken_option
@loop_semantics_option
@click.option("--json", "as_json", is_flag=True)
def simulate(km: float, until_failure: bool, until_sensing_failure: bool, seed: int, engine: str, strategy: Strategy,
             cell_m: float, model: str, runs: int,
             workers: int, executor_kind: str, scheduler: str | None, out_dir: str, fresh: bool,
             step_tolerance: float, plan_tolerance: float, paper_replanning: bool, faults: str,
             steering_offset_deg: float, tracking: bool, vehicle_speeds: VehicleSpeeds, overtaken: Overtaken,
             semantics: Semantics | None, as_json: bool) -> None:
    """Drive the PyBullet simulator closed-loop and check every action against the model's prediction."""
    from ci.audit.campaign import decider
    from ci.shared.progress import km_progress
    from ci.simulation.campaign import RUNS_FILE
    from ci.simulation.campaign import simulate as run_campaign
    from sim.parts import DriveConfig
    from sim.tables import deviations_table, faults_table, paper_table, runs_table, totals_table

    executor = ExecutorChoice(ExecutorKind(executor_kind), workers, scheduler)
    check_executor(executor)
    out_dir_checked("--out", out_dir)
    click.get_current_context().with_resource(campaign_lock(Path(out_dir)))  # before any line: one campaign per folder
    if seed + runs - 1 >= 2**32:
        raise OptionError("--seed", seed, f"seed + runs - 1 must stay below 2**32 (runs {runs})")
    campaign = DriveConfig(km, until_failure, engine, strategy, not paper_replanning, step_tolerance, plan_tolerance,
                           cell_m, model=model, faults=faults, steering_offset_deg=steering_offset_deg,
                           tracking=tracking, until_sensing_failure=until_sensing_failure,
                           vehicle_speeds=vehicle_speeds, overtaken=overtaken, semantics=semantics)
    if vehicle_speeds is VehicleSpeeds.MEASURED and model != "sound":
        raise OptionError("--vehicle-speeds", vehicle_speeds.value, "needs --model sound (the paper's rules read "
                          "cells alone)")
    campaign.parts()  # the engine exists and answers the strategy: bad input before any run starts
    get_engine(engine).ready()  # its tools are installed (exit 4), or every plan of every run would fail
    limit = f"{km:g} km" + (" or until failure" if until_failure else "") + (
        " or until a failure a sensing fault caused (others restart the drive)" if until_sensing_failure else "")
    print_header(err, f"seeds {seed}..{seed + runs - 1}; {runs} run(s) of {limit}; "
              f"model {decider(model, campaign.decides.value)}; engine {engine}, "
              f"{strategy.value}, {campaign.grid.describe()}; faults {campaign.faults or 'none'}; "
              f"tracking {'on' if tracking else 'off'}; "
              f"on {executor.describe(runs)}", Path(out_dir) / RUNS_FILE)
    resumed = f"already in {RUNS_FILE} (resumed; --fresh runs it again)"
    with km_progress(err, runs, km, resumed) as bar:
        results = run_campaign(campaign, list(range(seed, seed + runs)), out_dir, executor, bar.done, fresh,
                               bar.moved)
    if as_json:
        print_json([r.to_json() for r in results])
    else:
        for table in (runs_table(results), totals_table(results), deviations_table(results)):
            print_table(table, 1, "runs.jsonl")
        if campaign.stops_at_failure:
            print_table(paper_table(results, km, until_sensing_failure), 1, "runs.jsonl")
        if campaign.faults:
            print_table(faults_table(results), 1, "runs.jsonl")
    sys.exit(ExitCode.NO if any(r.failures for r in results) else ExitCode.OK)


COMMANDS = (simulate,)
