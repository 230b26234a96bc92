"""The sound model's planning in the closed loop, per engine, against the control step it assumes; and Spin compiling
a verifier per snapshot, on the same snapshots, in one run.

Usage: python -m ci.bench.loop [--km 2] [--seeds 1,2,3] [--engines interpreter,spin] [--cells 21]
                               [--traffic paper] [--sensor exact] [--compiled 10] [--commitments 40]
                               [--commitment-engines interpreter,spin,z3] [--timeout 10] [--semantics commit]

Every engine drives the same seeds under the sound model (``sensible``), deciding by whole plans or (``--semantics
commit``) by committed parts with their escapes, as ``overtake simulate --semantics`` does; each plan's time is the
pipeline's as the drive counts it (``RunSummary.plan_ms``: final model, then preparations; every new measured speed of
the AV builds its table), and a plan over ``LOOP.plan_budget_s`` is counted, never dropped. The drives must be the same
whoever plans (the sensible plans are the same plans). Then ``--compiled`` of the first Spin drives' snapshots (one of
each ``SNAPSHOT_EVERY`` plans) are planned twice: by the served verifier, its tables built afresh as a new speed's are
in the loop, and by a verifier compiled for the snapshot (``promela.runner.search_compiling``: spin -a, gcc, pan); each
through the pipeline as a drive times it (``oracle.planner.solve``: without the interpreter's checks of the answer that
``plan`` adds after the clock stops). Last, ``--commitments`` snapshots of the first engine's drives are planned by each
of ``--commitment-engines`` under the commitment semantics (``spec.commitment``; sensible where the engine answers it,
else shortest; Spin's tables built afresh, as a new speed's; past ``--timeout`` seconds an answer is incomplete,
counted): what a decision costs when the loop commits, for every engine, Z3 among them.
"""

from __future__ import annotations

import argparse

import numpy as np
from rich.console import Console
from rich.table import Table

from ci.bench.latency import timed
from ci.bench.sim import drives_match
from ci.shared.machine import machine
from oracle.planner import solve
from promela import runner
from promela import sound as sound_model
from sim.parts import DriveConfig
from sim.simulator import run_drive
from sim.summary import RunSummary
from spec import windows
from spec.answers import Limits, Status, Strategy
from spec.engines import Engine, get_engine, under_semantics
from spec.escapes import Semantics
from spec.files import scenario_from_dict
from spec.physical import LOOP
from spec.scenario import Scenario

COMPILING = Engine("spin, a verifier compiled per snapshot", (Strategy.SENSIBLE,),
                   lambda p, s, limits: runner.search_compiling(p, s, limits.timeout_s),
                   "Spin, the sound model's verifier compiled for every snapshot (benchmark only)", sound=True)
TARGET_MEDIAN_MS, TARGET_P99_MS, TARGET_RATIO, TARGET_OVER = 20.0, 50.0, 100.0, 0.01


def _fresh_tables() -> None:
    """Forget every table a speed built (the shapes of the actions' speeds stay, as in a drive): the next plan
    builds its table as a new measured speed's is built in the loop."""
    windows.forget_tables()
    sound_model.table_text.cache_clear()
    runner._table_data.cache_clear()


def _served(scenario: Scenario) -> object:
    _fresh_tables()
    return solve(scenario, Strategy.SENSIBLE, engine="spin")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--km", type=float, default=2.0)
    parser.add_argument("--seeds", default="1,2,3")
    parser.add_argument("--engines", default="interpreter,spin")
    parser.add_argument("--cells", type=float, default=21.0)
    parser.add_argument("--traffic", default="paper")
    parser.add_argument("--sensor", default="exact")
    parser.add_argument("--compiled", type=int, default=10, help="snapshots planned by compiling a verifier each")
    parser.add_argument("--commitment-engines", default=None, help="the engines that plan those snapshots under the "
                        "commitment semantics (default: --engines)")
    parser.add_argument("--timeout", type=float, default=10.0, help="seconds per commitment, past them incomplete")
    parser.add_argument("--commitments", type=int, default=40, help="snapshots planned under the commitment "
                        "semantics by each engine")
    parser.add_argument("--semantics", choices=[s.value for s in Semantics], default=Semantics.COMMIT.value,
                        help="how the drives' sound model decides")
    args = parser.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    engines = [e.strip() for e in args.engines.split(",")]
    console = Console(width=140)
    budget_ms = LOOP.plan_budget_s * 1000
    console.print(f"seeds {args.seeds}; {args.km} km each; sound model ({args.semantics}), sensible; {args.cells:g} m "
                  f"cells; traffic "
                  f"{args.traffic}, sensor {args.sensor}; engines {args.engines}; budget {budget_ms:.1f} ms per plan; "
                  f"one process; {runner.tool_versions()}; {machine()}")
    runs: dict[str, list[RunSummary]] = {}
    for engine in engines:
        runs[engine] = []
        for seed in seeds:
            kept = args.compiled if engine == "spin" else args.commitments if engine == engines[0] else 0
            config = DriveConfig(args.km, engine=engine, model="sound", cell_m=args.cells, traffic=args.traffic,
                                 sensor=args.sensor, snapshots=kept, semantics=Semantics(args.semantics))
            runs[engine].append(run_drive(seed, config))
            console.print(f"  {engine} seed {seed}: {runs[engine][-1].plans} plans, {runs[engine][-1].km:.2f} km")
    reference = engines[0]
    table = Table(title=f"planning in the closed loop, sound model ({args.semantics}) (ms per plan, whole pipeline)")
    for col in ("engine", "plans", "median", "p99", "max", f"over {budget_ms:.0f} ms", "same drives as " + reference):
        table.add_column(col, justify="right")
    verdicts = []
    for engine, results in runs.items():
        ms = np.array([m for r in results for m in r.plan_ms])
        over = int((ms > budget_ms).sum())
        same = all(drives_match(a, b) for a, b in zip(runs[reference], results, strict=True))
        table.add_row(engine, str(len(ms)), f"{np.median(ms):.2f}", f"{np.percentile(ms, 99):.2f}", f"{ms.max():.2f}",
                      f"{over} ({over / len(ms):.1%})", "yes" if same else "NO")
        verdicts.append((engine, ms, over / len(ms), same))
    console.print(table)
    for engine, ms, share, same in verdicts:
        if engine == "spin":
            ok = np.median(ms) <= TARGET_MEDIAN_MS and np.percentile(ms, 99) <= TARGET_P99_MS
            console.print(f"target: spin's median <= {TARGET_MEDIAN_MS:g} ms and p99 <= {TARGET_P99_MS:g} ms: "
                          f"{'met' if ok else 'NOT met'} ({np.median(ms):.2f} / {np.percentile(ms, 99):.2f})")
        console.print(f"target: {engine}'s plans over the budget <= {TARGET_OVER:.0%}: "
                      f"{'met' if share <= TARGET_OVER else 'NOT met'} ({share:.1%}); same drives: "
                      f"{'yes' if same else 'NO'}")
    committing = engines if args.commitment_engines is None else \
        [e.strip() for e in args.commitment_engines.split(",") if e.strip()]
    for engine in committing:
        get_engine(engine)  # an unknown name: bad input before the drives' results are printed
    _commitments(console, [scenario_from_dict(s) for r in runs[reference] for s in r.snapshots][: args.commitments],
                 committing, budget_ms, args.timeout)
    # whole plans: the verifier compiled per snapshot answers the sound model's whole plans only
    snapshots = [under_semantics(scenario_from_dict(s), Semantics.WHOLE) for r in runs.get("spin", [])
                 for s in r.snapshots][: args.compiled]
    if not snapshots:
        return
    get_engine("spin").ready()
    served = timed(snapshots, _served)
    compiled = timed(snapshots, lambda s: solve(s, Strategy.SENSIBLE, engine=COMPILING))
    table = Table(title=f"the same {len(snapshots)} snapshots of the Spin drives (ms per plan, whole pipeline)")
    for col in ("pipeline", "n", "median", "p99", "max", "median vs served"):
        table.add_column(col, justify="right")
    for name, ms in (("spin, served (a new speed's table built)", served), (COMPILING.name, compiled)):
        table.add_row(name, str(len(ms)), f"{np.median(ms):.2f}", f"{np.percentile(ms, 99):.2f}", f"{ms.max():.2f}",
                      f"{np.median(ms) / np.median(served):.0f}x")
    console.print(table)
    ratio = np.median(compiled) / np.median(served)
    console.print(f"target: served >= {TARGET_RATIO:g}x faster than compiling per snapshot: "
                  f"{'met' if ratio >= TARGET_RATIO else 'NOT met'} ({ratio:.0f}x)")


def _commitments(console: Console, snapshots: list[Scenario], engines: list[str], budget_ms: float,
                 timeout_s: float) -> None:
    """The snapshots under the commitment semantics, per engine: ms per answer (the pipeline's, unchecked; Spin's
    tables built afresh) against the budget, which answers are commitments and which are incomplete."""
    committed = [under_semantics(s, Semantics.COMMIT) for s in snapshots if s.sound is not None]
    if not committed:
        return
    table = Table(title=f"the first drives' {len(committed)} snapshots under the commitment semantics (ms per answer)")
    for col in ("engine", "strategy", "n", "median", "p99", "max", f"over {budget_ms:.0f} ms", "commitments",
                f"incomplete ({timeout_s:g} s)"):
        table.add_column(col, justify="right")
    for engine in engines:
        answers: list[Status] = []
        strategy = Strategy.SENSIBLE if Strategy.SENSIBLE in get_engine(engine).strategies else Strategy.SHORTEST

        def run(scenario: Scenario, engine: str = engine, answers: list[Status] = answers,
                strategy: Strategy = strategy) -> None:
            if engine == "spin":
                _fresh_tables()
            answers.append(solve(scenario, strategy, engine=engine, limits=Limits(timeout_s=timeout_s)).status)

        ms = timed(committed, run)
        over = int((ms > budget_ms).sum())
        table.add_row(engine, strategy.value, str(len(ms)), f"{np.median(ms):.2f}", f"{np.percentile(ms, 99):.2f}",
                      f"{ms.max():.2f}", f"{over} ({over / len(ms):.1%})",
                      str(sum(s is Status.PLAN for s in answers[1:])),
                      str(sum(s is Status.INCOMPLETE for s in answers[1:])))
    console.print(table)


if __name__ == "__main__":
    main()
