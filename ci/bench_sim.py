"""Simulated kilometres per wall-clock minute on one core, closed loop with the interpreter planner.

Usage: python -m ci.bench_sim [--km 10] [--seeds 1,2,3]
"""

from __future__ import annotations

import argparse

import numpy as np
from rich.console import Console
from rich.table import Table

from ci.bench import machine
from sim.simulator import Simulator
from spec.physical import LOOP


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--km", type=float, default=10.0)
    parser.add_argument("--seeds", default="1,2,3")
    args = parser.parse_args()
    console = Console(width=120)
    console.print(f"seeds {args.seeds}; {args.km} km each; physics dt {LOOP.physics_dt_s:.4f} s, control every "
                  f"{LOOP.control_every_steps} steps; one process; {machine()}")
    table = Table(title="closed-loop simulation speed")
    for col in ("seed", "km", "sim time (min)", "wall (s)", "km per wall minute", "x real time", "plans",
                "plan ms (median)", "failure"):
        table.add_column(col, justify="right")
    rates = []
    for seed in (int(s) for s in args.seeds.split(",")):
        sim = Simulator(seed)
        try:
            r = sim.drive(args.km)
        finally:
            sim.close()
        rate = r.km / (r.wall_s / 60)
        rates.append(rate)
        table.add_row(str(seed), f"{r.km:.2f}", f"{r.sim_time_s / 60:.1f}", f"{r.wall_s:.1f}", f"{rate:.1f}",
                      f"{r.sim_time_s / r.wall_s:.0f}x", str(r.plans), f"{np.median(r.plan_ms):.2f}",
                      r.failure.cause if r.failure else "-")
    console.print(table)
    console.print(f"target: >= 30 km per wall minute on one core: {'met' if min(rates) >= 30 else 'NOT met'} "
                  f"(median {np.median(rates):.1f})")


if __name__ == "__main__":
    main()
