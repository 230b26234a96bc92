"""Whether fewer contact-solver iterations would buy physics time at the same physics: step cost and the AV's motion.

Usage: python -m ci.bench.solver [--iterations 50,20,10] [--rounds 2]

PyBullet solves the joints and the wheels' contacts with ``numSolverIterations`` (50 unless set; the simulator
never sets it). For each count the AV alone drives the same commands twice over: open loop (the common speed, twice
it and half it, 33 s each, a 0.1 rad steering pulse at 42 s) and through the executor (start-up, then drive,
accelerate, right_lane_change, left_lane_change, brake: the lane keeping and position reference the drives use).
Printed per count: µs per ``stepSimulation`` (median over rounds), the open loop's heading after its first 33 s at
7 m/s and its end position's distance from the first count's, and the executor's largest position and speed
difference from the first count's at matching steps. The first count is the reference.
"""

from __future__ import annotations

import argparse
import math
import statistics

from rich.console import Console
from rich.table import Table

from ci.bench.physics import StepTimer
from ci.shared.machine import machine
from sim.executor import Executor
from sim.scene import Scene
from sim.vehicle import Pose, WheeledCar
from spec.actions import Action
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.physical import LOOP

OPEN_LOOP_STEPS = 6000  # 100 s at 60 Hz
COMMON_MPS = PAPER_GRID.speed  # the open loop drives at it, twice it and half it
PLAN = (Action.DRIVE, Action.ACCELERATE, Action.RIGHT_LANE_CHANGE, Action.LEFT_LANE_CHANGE, Action.BRAKE)


def scene_with(iterations: int) -> Scene:
    """A scene whose contact solver runs ``iterations`` iterations a step."""
    scene = Scene()
    scene.client.setPhysicsEngineParameter(numSolverIterations=iterations)
    return scene


def open_loop(iterations: int) -> tuple[float, list[Pose]]:
    """µs per step, and the poses after each third of the drive."""
    scene = scene_with(iterations)
    car = WheeledCar(scene, 0.0, 0.0)
    poses = []
    with StepTimer() as timer:
        for k in range(OPEN_LOOP_STEPS):
            speed_mps = COMMON_MPS if k < 2000 else 2 * COMMON_MPS if k < 4000 else COMMON_MPS / 2
            car.command(speed_mps, 0.1 if 2500 <= k < 2600 else 0.0, scene.dt_s)
            scene.step()
            if k % 2000 == 1999:
                poses.append(car.pose())
    scene.close()
    return timer.seconds / timer.steps * 1e6, poses


def executed(iterations: int) -> list[Pose]:
    """The AV's pose at every control step of a start-up and a plan, through the executor."""
    scene = scene_with(iterations)
    car = WheeledCar(scene, 0.0, scene.lane_y(Lane.LEFT))
    executor = Executor(scene, car, Lane.LEFT, PAPER_GRID)
    poses: list[Pose] = []

    def tick(_dt_s: float) -> bool:
        poses.append(car.pose())
        return True

    executor.hold(10.0, PAPER_GRID.speed, tick)
    executor.reset_reference()
    for action in PLAN:
        executor.run(action, tick)
    scene.close()
    return poses


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--iterations", default="50,20,10")
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args()
    counts = [int(c) for c in args.iterations.split(",")]
    console = Console(width=140)
    console.print(f"AV alone, {LOOP.physics_dt_s:.4f} s steps; {args.rounds} round(s); {machine()}")
    table = Table(title="contact-solver iterations: step cost and the AV's motion against the first count's")
    for column in ("iterations", "µs per step", "open loop: heading after 33 s at 7 m/s, rad",
                   "open loop: end position off by, m", "executor: position off by, m", "executor: speed off by, m/s"):
        table.add_column(column, justify="right")
    reference_open: list[Pose] | None = None
    reference_exec: list[Pose] | None = None
    for count in counts:
        runs = [open_loop(count) for _ in range(args.rounds)]
        us = statistics.median(r[0] for r in runs)
        poses, path = runs[0][1], executed(count)
        reference_open = reference_open or poses
        reference_exec = reference_exec or path
        end_off = math.hypot(poses[-1].x_m - reference_open[-1].x_m, poses[-1].y_m - reference_open[-1].y_m)
        pairs = list(zip(path, reference_exec, strict=True))
        position_off = max(math.hypot(a.x_m - b.x_m, a.y_m - b.y_m) for a, b in pairs)
        speed_off = max(abs(a.speed_mps - b.speed_mps) for a, b in pairs)
        table.add_row(str(count), f"{us:.1f}", f"{poses[0].yaw_rad:.3f}", f"{end_off:.2f}", f"{position_off:.3f}",
                      f"{speed_off:.3f}")
    console.print(table)


if __name__ == "__main__":
    main()
