"""Commands about what is built in: the scenario library, the engines, and the demo of both."""

from __future__ import annotations

import sys

import click
from rich.table import Table

from ci.cli.common import SHORT, SHORT_STATUS, STATUS_LEGEND, abbrev, out, print_json, print_table, strategy_option
from oracle.conform import disagreements
from oracle.planner import plan as run_plan
from spec.answers import Strategy
from spec.engines import get_engine, load_engines
from spec.errors import ExitCode
from spec.escapes import Semantics
from spec.library import BUILTINS


@click.command()
@click.option("--json", "as_json", is_flag=True)
def scenarios(as_json: bool) -> None:
    """List the built-in scenarios and their expected outcomes."""
    if as_json:
        print_json([{"name": b.name, "description": b.description, "path": str(b.path),
                     "expected": b.expected.status.value, "model": b.expected.model.value} for b in BUILTINS])
        return
    table = Table(title="built-in scenarios")
    for col in ("name", "description", "expected", "model"):
        table.add_column(col)
    for b in BUILTINS:
        table.add_row(b.name, b.description, SHORT_STATUS[b.expected.status], b.expected.model.value)
    print_table(table)
    out.print(f"({STATUS_LEGEND})")


@click.command()
def engines() -> None:
    """List the registered engines: the strategies each answers, the sound model's semantics, and under which of
    them it answers measured speeds and the no-acceleration profile."""
    table = Table(title="engines")
    for col in ("engine", "strategies", "sound model", "measured speeds", "no-acceleration", "description"):
        table.add_column(col)
    for engine in load_engines().values():
        semantics = [Semantics.WHOLE] * engine.sound + [Semantics.COMMIT] * engine.commit
        table.add_row(engine.name, ", ".join(s.value for s in engine.strategies), _under(tuple(semantics)),
                      _under(engine.measured_speeds), _under(engine.overtaken_profile), engine.description)
    print_table(table)


def _under(semantics: tuple[Semantics, ...]) -> str:
    """The semantics a feature is answered under, in the options' words ("-": none)."""
    return ", ".join(s.value for s in sorted(semantics, key=lambda s: s.value, reverse=True)) or "-"


@click.command()
@strategy_option()
@click.option("--engine", "engine_names", multiple=True, help="Engines to run (default: every registered one).")
def demo(strategy: Strategy, engine_names: tuple[str, ...]) -> None:
    """Plan every built-in scenario with every engine, side by side; exit 1 on any unexpected answer."""
    chosen = [get_engine(name) for name in engine_names] or list(load_engines().values())
    engines = [e for e in chosen if strategy in e.strategies]
    table = Table(title=f"overtake demo: built-in scenarios, strategy {strategy.value}")
    table.add_column("scenario", no_wrap=True)
    table.add_column("expected")
    for engine in engines:
        table.add_column(f"{engine.name}: plan, ms")
    table.add_column("agree")
    unexpected = 0
    for b in BUILTINS:
        answers = [run_plan(b.load(), strategy, engine=e) for e in engines]
        cells = []
        for engine, a in zip(engines, answers):
            ok = b.expected.matches(a, engine.prove_beyond is not None)
            unexpected += not ok
            cells.append(f"{abbrev(a, compact=True)} {a.elapsed_ms:.1f}" + ("" if ok else " UNEXPECTED"))
        expected = f"{SHORT_STATUS[b.expected.status]}, {b.expected.model.value}"
        table.add_row(b.name, expected, *cells, "yes" if not disagreements(answers) else "NO")
    print_table(table, 2, "a wider terminal")
    out.print("plans: " + ", ".join(f"{letter} {action.value}" for action, letter in SHORT.items())
              + f"; {STATUS_LEGEND}; ms per plan, whole pipeline")
    out.print("all answers as expected" if not unexpected else f"{unexpected} answer(s) differ from expectation")
    _demo_drive()
    sys.exit(ExitCode.NO if unexpected else ExitCode.OK)


def _demo_drive(km: float = 1.0, seed: int = 1) -> None:
    """A short closed-loop drive in the PyBullet simulator, summarised in two lines."""
    from sim.parts import DriveConfig  # PyBullet loads only when asked for
    from sim.simulator import run_drive

    r = run_drive(seed, DriveConfig(km))
    largest = ", ".join(f"{a} {d:.2f}" for a, d in sorted(r.tolerance.largest.items()))
    out.print(f"simulated drive (seed {seed}): {r.km:.2f} km in {r.sim_time_s / 60:.1f} simulated min "
              f"({r.wall_s:.1f} s wall), {r.overtakes} overtakes, {r.plans} plans, "
              f"{'no collision' if not r.collisions else r.collisions[0].cause + ', ' + r.collisions[0].detail}")
    out.print(f"  largest deviation from the model per action (cells): {largest}; "
              f"{r.tolerance.violation_count} beyond tolerance (`overtake simulate` for more)")


COMMANDS = (scenarios, engines, demo)
