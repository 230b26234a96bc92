"""The audit's physics floor: how much of its wall time is PyBullet's own stepping, which no Python change can save.

Usage: python -m ci.bench.physics [--km 1] [--cells 21,10.5,7,5.25] [--default-km KM] [--workers 2]

Runs ``overtake audit`` in this process (``--workers 1 --runs 1 --engines interpreter --snapshots 0``), one model at a
time over the audit's default grid (every cell size, traffic and sensing model), with a timer around each physics
step (``sim.scene.Scene.step``: one ``stepSimulation`` at the stated 60 Hz, the drives' and the missed-opportunity
replays' alike), and prints per model: km driven, wall seconds, physics steps, their seconds and share, and what the
default audit (``--default-km`` per combination, by default the command's own ``--km`` x ``--runs``) takes at that
rate on ``--workers`` processes, in all, in physics alone (the floor below which the audit's closed loop cannot go at
this fidelity on this machine) and in the drives' physics without the missed-opportunity replays (the floor if those
were dropped).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import click
from rich.console import Console
from rich.table import Table

from ci.audit.campaign import AuditPlan
from ci.cli.audit import audit as audit_command
from ci.cli.audit import parse_cells
from ci.cli.main import cli
from ci.shared.machine import machine
from ci.shared.options import names
from sim.opportunity import Replay
from sim.scene import Scene
from spec.errors import OptionError, SuiteError, check_number
from spec.physical import LOOP

#: The audit command's defaults (its grid, models, km, runs and workers), read from its options.
DEFAULTS: dict[str | None, Any] = {param.name: param.default for param in audit_command.params}


class StepTimer:
    """Wall seconds and count of every ``Scene.step`` while installed (a context manager), and of those taken in
    missed-opportunity replays (``sim.opportunity.Replay.first_success``)."""

    def __init__(self) -> None:
        self.steps, self.seconds, self.replay_steps, self.replay_seconds = 0, 0.0, 0, 0.0
        self._replaying = False

    def __enter__(self) -> StepTimer:
        self._step, self._replay = step, replay = Scene.step, Replay.first_success

        def timed(scene: Scene) -> None:
            started = time.perf_counter()
            step(scene)
            seconds = time.perf_counter() - started
            self.seconds, self.steps = self.seconds + seconds, self.steps + 1
            if self._replaying:
                self.replay_seconds, self.replay_steps = self.replay_seconds + seconds, self.replay_steps + 1

        def replaying(this: Replay, target: Any) -> Any:
            self._replaying = True
            try:
                return replay(this, target)
            finally:
                self._replaying = False

        setattr(Scene, "step", timed)  # noqa: B010 (methods replaced for the measurement)
        setattr(Replay, "first_success", replaying)  # noqa: B010
        return self

    def __exit__(self, *_: object) -> None:
        setattr(Scene, "step", self._step)  # noqa: B010
        setattr(Replay, "first_success", self._replay)  # noqa: B010


def audit_one_model(model: str, km: float, cells: str, out: Path) -> tuple[float, float, StepTimer]:
    """One in-process ``overtake audit`` of ``model`` over the default grid: wall seconds, km driven, physics."""
    args = ["audit", "--model", model, "--cells", cells, "--km", str(km), "--runs", "1", "--engines", "interpreter",
            "--snapshots", "0", "--workers", "1", "--out", str(out), "--fresh"]
    with StepTimer() as timer, contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        started = time.perf_counter()
        try:
            code = cli.main(args, standalone_mode=False)
        except SystemExit as done:
            code = done.code
        except click.ClickException as error:  # bad input the audit's options refused (--cells): one line, exit 2
            raise OptionError("--cells", cells, error.format_message()) from None
        wall_s = time.perf_counter() - started
    if code not in (0, None):
        raise SuiteError(f"the audit of model {model} exited {code}")
    rows = json.loads((out / "audit.json").read_text())["combinations"]
    return wall_s, sum(r["km"] for r in rows), timer


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--km", type=float, default=1.0, help="km per combination (one run each)")
    parser.add_argument("--cells", default=str(DEFAULTS["cells"]), help="cell lengths, comma-separated")
    parser.add_argument("--default-km", type=float, default=float(DEFAULTS["km"]) * int(DEFAULTS["runs"]),
                        help="km per combination of the default audit (its --km x --runs)")
    parser.add_argument("--workers", type=int, default=int(DEFAULTS["workers"]),
                        help="processes the default audit runs on (its --workers)")
    args = parser.parse_args()
    try:
        measure(args)
    except SuiteError as error:
        print(f"bench_physics: error: {error}", file=sys.stderr)
        sys.exit(error.exit_code)


def measure(args: argparse.Namespace) -> None:
    """The table (see the module's docstring), for checked options."""
    check_number("--km", args.km, positive=True)
    check_number("--default-km", args.default_km, positive=True)
    check_number("--workers", args.workers, low=1)
    cells_m = parse_cells(args.cells)  # the audit's own check of the list: one line naming the bad length
    models = names("--model", str(DEFAULTS["model_text"]))
    per_model = len(AuditPlan(models=models[:1], cells_m=cells_m).configs())
    console = Console(width=150)
    console.print(f"overtake audit --model M --cells {args.cells} --km {args.km} --runs 1 --engines interpreter "
                  f"--snapshots 0 --workers 1 (in process): {per_model} combinations per model; {machine()}")
    table = Table(title=f"the audit's physics floor (PyBullet stepSimulation at {1 / LOOP.physics_dt_s:g} Hz)")
    for col in ("model", "km driven", "wall s", "physics steps", "of them in replays", "physics s", "µs per step",
                "physics share", f"default audit ({args.default_km:g} km x {per_model}, {args.workers} workers) min",
                "of it physics alone min", "of it the drives' physics min"):
        table.add_column(col, justify="right")
    total_min = physics_min = drives_min = 0.0
    with tempfile.TemporaryDirectory() as scratch:
        for model in models:
            wall_s, km, timer = audit_one_model(model, args.km, args.cells, Path(scratch) / model)
            scale = args.default_km * per_model / km / args.workers / 60
            drives_s = timer.seconds - timer.replay_seconds
            total_min, physics_min = total_min + wall_s * scale, physics_min + timer.seconds * scale
            drives_min += drives_s * scale
            table.add_row(model, f"{km:.1f}", f"{wall_s:.1f}", f"{timer.steps:,}", f"{timer.replay_steps:,}",
                          f"{timer.seconds:.1f}", f"{1e6 * timer.seconds / max(timer.steps, 1):.0f}",
                          f"{timer.seconds / wall_s:.0%}", f"{wall_s * scale:.1f}", f"{timer.seconds * scale:.1f}",
                          f"{drives_s * scale:.1f}")
    table.add_row("all", "", "", "", "", "", "", f"{physics_min / total_min:.0%}", f"{total_min:.1f}",
                  f"{physics_min:.1f}", f"{drives_min:.1f}")
    console.print(table)
    console.print("(the projection scales each model's wall time, start-up and plots included, by km: an upper bound "
                  "on the whole and a fair one on the physics, which grows with km alone)")


if __name__ == "__main__":
    main()
