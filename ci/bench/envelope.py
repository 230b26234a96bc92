"""The AV's envelope, measured: how far the car strays from the reference the sound model's proofs bound it about.

Usage: python -m ci.bench.envelope [--traffic paper,spread,following] [--seeds 1-10] [--km 25] [--cell-m 21]
       [--sensor exact] [--workers 2]

Drives the sound model in the closed loop (one drive per traffic model and seed, ``--workers`` processes) and reads,
at every control step where a sound decision holds the AV to its envelope (``SoundDriver.enveloped``: a plan, a kept
proof, a proved minimal-risk manoeuvre; not the start-up, nor the fallback's take-over, whose reference restarts at
the car), the car's distance from its position reference and its speed's from the reference speed, as containment's
check of the AV reads them (``Containment.check_av``). Prints per traffic model: km, control steps read, the 50th,
90th, 99th and 99.9th percentiles and the maximum of each, the AV-envelope breaches containment counted, and the
decisions that planned from the reference (``reference_starts``). The envelope the proofs take is
``spec.envelope.TRACKING`` (rule: the maximum, rounded up to 0.5: docs/sound.md, "The AV's envelope").
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass

import numpy as np
from rich.console import Console
from rich.table import Table

from ci.shared.machine import machine
from ci.shared.options import names
from sim.parts import DriveConfig
from sim.simulator import Simulator, assemble
from sim.vehicle import Pose
from spec.envelope import TRACKING
from spec.errors import OptionError, SuiteError, check_number

#: The percentiles the table prints (the maximum besides).
PERCENTILES = (50.0, 90.0, 99.0, 99.9)


class Measured(Simulator):
    """A simulator that keeps, at each control step where the sound driver holds the AV to its envelope, the car's
    position and speed off its reference."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        self.off_m: list[float] = []
        self.off_mps: list[float] = []
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]

    def _contain(self, pose: Pose, dt_s: float) -> None:
        driver = self.sound_driver
        if dt_s and driver is not None and driver.enveloped:
            self.off_m.append(abs(pose.x_m - self.executor.x_ref_m))
            self.off_mps.append(abs(pose.along_mps - self.executor.v_ref_mps))
        super()._contain(pose, dt_s)


@dataclass(frozen=True)
class Drive:
    """One drive's deviations and counts."""

    traffic: str
    seed: int
    km: float
    off_m: np.ndarray
    off_mps: np.ndarray
    breaches: int
    reference_starts: int
    plans: int


def drive(seed: int, config: DriveConfig) -> Drive:
    """One drive of ``config`` on ``seed`` (the unit a worker runs)."""
    measured = assemble(seed, config, simulator=Measured)
    assert isinstance(measured, Measured)
    try:
        summary = measured.drive(config.km)
    finally:
        measured.close()
    return Drive(config.traffic, seed, summary.km, np.array(measured.off_m), np.array(measured.off_mps),
                 summary.containment.by_kind.get("AV envelope", 0), summary.reference_starts, summary.plans)


def seeds_from(text: str) -> list[int]:
    """``A-B`` or ``A,B,...``: the seeds (each at least 0); anything else names ``--seeds``."""
    try:
        if "-" in text.strip("-"):
            low, high = (int(part) for part in text.split("-", 1))
            found = list(range(low, high + 1))
        else:
            found = [int(part) for part in text.split(",")]
    except ValueError:
        raise OptionError("--seeds", text, "must be A-B or A,B,... of whole numbers") from None
    if not found or min(found) < 0:
        raise OptionError("--seeds", text, "must name at least one seed, none below 0")
    return found


def options() -> argparse.ArgumentParser:
    """The command line (the module's docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    for name, kind, default, say in (("--traffic", str, "paper,spread,following", "traffic models, comma-separated"),
                                     ("--seeds", str, "1-10", "seeds: A-B or A,B,..."),
                                     ("--km", float, 25.0, "km per drive"),
                                     ("--cell-m", float, 21.0, "the planner's cell length, m"),
                                     ("--sensor", str, "exact", "the sensor model (exact, noisy)"),
                                     ("--workers", int, 2, "processes")):
        parser.add_argument(name, type=kind, default=default, help=say)
    return parser


def main() -> None:
    """Measure; bad input is one line and its exit code, an interrupt exits 130."""
    args = options().parse_args()
    code, said = 0, ""
    try:
        measure(args)
    except SuiteError as error:
        code, said = error.exit_code, f"error: {error}"
    except KeyboardInterrupt:
        code, said = 130, "interrupted; nothing measured is kept"
    if code:
        print(f"bench_envelope: {said}", file=sys.stderr)
        sys.exit(code)


def measure(args: argparse.Namespace) -> None:
    """The table (see the module's docstring), for checked options."""
    check_number("--km", args.km, positive=True)
    check_number("--workers", args.workers, low=1, high=256)
    traffic = names("--traffic", args.traffic)
    seeds = seeds_from(args.seeds)
    configs = {name: DriveConfig(args.km, model="sound", traffic=name, cell_m=args.cell_m, sensor=args.sensor,
                                 snapshots=0, opportunity_checks=0, restart_after_collision=True) for name in traffic}
    for config in configs.values():
        config.parts()  # bad input (a traffic model, the cell length, the sensor) named before any worker starts
    console = Console(width=150)
    console.print(f"python -m ci.bench.envelope --traffic {args.traffic} --seeds {args.seeds} --km {args.km:g} "
                  f"--cell-m {args.cell_m:g} --sensor {args.sensor} --workers {args.workers}; {machine()}")
    drives: list[Drive] = []
    jobs = [(name, seed) for name in traffic for seed in seeds]
    with ProcessPoolExecutor(args.workers) as pool:
        futures = [pool.submit(drive, seed, configs[name]) for name, seed in jobs]
        for done, future in enumerate(as_completed(futures), 1):
            found = future.result()
            drives.append(found)
            console.print(f"[{done}/{len(jobs)}] {found.traffic} seed {found.seed}: {found.km:.1f} km, "
                          f"max {found.off_m.max(initial=0.0):.2f} m, {found.off_mps.max(initial=0.0):.2f} m/s")
    table = Table(title=f"the car off its reference under the sound model (the envelope: {TRACKING.position_m:g} m, "
                        f"{TRACKING.speed_mps:g} m/s)")
    for col in ("traffic", "km", "steps", "", *(f"p{p:g}" for p in PERCENTILES), "max", "envelope breaches",
                "plans from the reference"):
        table.add_column(col, justify="right")
    for name in traffic:
        mine = [d for d in drives if d.traffic == name]
        for what, unit in (("off_m", "|x - x_ref| m"), ("off_mps", "|v - v_ref| m/s")):
            values = np.concatenate([getattr(d, what) for d in mine])
            cells = [f"{q:.2f}" for q in np.percentile(values, PERCENTILES)] if values.size else ["-"] * 4
            first = what == "off_m"
            table.add_row(name if first else "", f"{sum(d.km for d in mine):.1f}" if first else "",
                          f"{values.size:,}" if first else "", unit, *cells,
                          f"{values.max():.2f}" if values.size else "-",
                          str(sum(d.breaches for d in mine)) if first else "",
                          f"{sum(d.reference_starts for d in mine):,} of {sum(d.plans for d in mine):,}" if first
                          else "")
    console.print(table)


if __name__ == "__main__":
    main()
