"""The simulator's physical parameters: road, vehicles, sensors, traffic rules, re-planning and tolerances.

The discrete model's own mapping (cell length, common speed, each action's speed and
duration) is in ``spec.grid`` and ``spec.actions``; this module holds what only the
physical world needs, from the paper's simulator section and SPEC.md. The paper states its
traffic in cells of its 21 m grid (``PAPER_GRID``), whatever grid the planner uses.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from spec.grid import PAPER_GRID

_PAPER_CELL_M = PAPER_GRID.cell


@dataclass(frozen=True, slots=True)
class RoadSpec:
    """A straight two-lane road."""

    lane_width_m: float = 3.6


@dataclass(frozen=True, slots=True)
class CarSpec:
    """The AV: a car-sized chassis on four wheels, front-wheel steering, bounded acceleration and braking."""

    length_m: float = 4.5
    width_m: float = 1.8
    height_m: float = 1.2
    mass_kg: float = 1200.0
    wheel_radius_m: float = 0.32
    wheel_width_m: float = 0.22
    wheel_mass_kg: float = 15.0
    wheelbase_m: float = 2.7
    track_m: float = 1.55
    max_accel_mps2: float = 3.0
    max_brake_mps2: float = 6.0
    max_steer_rad: float = 0.45
    wheel_force_n: float = 4000.0  # per driven wheel: enough for max_brake_mps2 with four wheels


@dataclass(frozen=True, slots=True)
class SensorSpec:
    """The paper's three sensors (ranges in metres)."""

    left_range_m: float = 100.0  # 360-degree sensor for the left lane
    right_range_m: float = 17 * _PAPER_CELL_M  # front-right long-range sensor: 357 m, 17 cells
    side_range_m: float = 2 * _PAPER_CELL_M  # right-side sensor: what the front-right one cannot see
    height_m: float = 0.8  # rays are cast at this height, through the other cars' bodies


@dataclass(frozen=True, slots=True)
class TrafficSpec:
    """The paper's traffic: constant vehicle counts, respawn rules, removal behind the AV."""

    speed_mps: float = PAPER_GRID.speed  # every vehicle drives at the model's common speed, as in the paper
    cell_m: float = _PAPER_CELL_M  # the unit of the respawn gaps below
    left_vehicles: int = 6
    oncoming_vehicles: int = 3
    left_respawn_cells: tuple[int, ...] = (1, 2, 3, 4)  # ahead of the front-most, equal odds
    max_consecutive: int = 3  # never more than three left-lane vehicles without an empty cell
    oncoming_gap_cells: tuple[int, ...] = (8, 12, 16, 20)  # beyond the last oncoming vehicle
    oncoming_gap_odds: tuple[Fraction, ...] = (Fraction(1, 8), Fraction(1, 4), Fraction(1, 4), Fraction(3, 8))
    remove_behind_cells: int = 5


@dataclass(frozen=True, slots=True)
class LoopSpec:
    """Closed-loop driving: when to re-plan, how finely to simulate, how much to tolerate."""

    replan_after_actions: int = 10
    physics_dt_s: float = 1 / 60
    control_every_steps: int = 2  # the controller runs at physics rate / this
    # A lane change's sideways move is done within this much of the action's time: the model
    # flips the AV's lane before any oncoming tick, so the car must be in its new lane early.
    lane_change_lateral_s: float = 2.0
    step_tolerance_cells: float = 0.25  # per action, in tolerance units
    plan_tolerance_cells: float = 0.5  # accumulated since the plan started
    tolerance_unit_m: float = _PAPER_CELL_M  # tolerances count cells of the paper's grid, whatever the planner's
    wait_s: float = float(PAPER_GRID.time_unit_s)  # driving on without a plan (the paper's 3 s time unit)


ROAD, CAR, SENSORS, TRAFFIC, LOOP = RoadSpec(), CarSpec(), SensorSpec(), TrafficSpec(), LoopSpec()
