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
    # Sweeps per second, whenever the planner decides: a common automotive radar and lidar cycle (the paper does not
    # state its sensors' rate); every third control step of the 30 Hz controller.
    sweep_hz: float = 10.0


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
class SpeedSpec:
    """Per-vehicle speeds of the traffic models that do not keep to the grid (``spread``, ``following``).

    Normal around the paper's 7 m/s with a coefficient of variation of 0.1 (free-flow speeds on
    one road are commonly reported with a coefficient of variation of about 0.1-0.15; the low
    end is taken so that the AV at 7 m/s can still overtake the faster ones), cut at 3 sd.
    """

    mean_mps: float = PAPER_GRID.speed
    sd_mps: float = 0.1 * PAPER_GRID.speed
    cut_sd: float = 3.0


@dataclass(frozen=True, slots=True)
class IdmSpec:
    """The Intelligent Driver Model's parameters as published (Treiber, Hennecke and Helbing, Phys. Rev. E 62,
    1805 (2000), Table I), except the desired speed, which is drawn per vehicle around the paper's 7 m/s
    (``SpeedSpec``) instead of their 120 km/h; deceleration is bounded by what a car can do."""

    time_gap_s: float = 1.6  # T
    min_gap_m: float = 2.0  # s0, bumper to bumper
    accel_mps2: float = 0.73  # a
    comfortable_decel_mps2: float = 1.67  # b
    exponent: float = 4.0  # delta
    max_decel_mps2: float = 9.0  # a physical bound (about 0.9 g) on what the model may ask for


@dataclass(frozen=True, slots=True)
class EventSpec:
    """Events of the traffic models that do not keep to the grid, at stated rates (stress parameters, not
    measurements: every audit states them, and the command line can change them)."""

    stop_rate_per_h: float = 0.5  # a left-lane vehicle brakes to a standstill, per vehicle-hour
    stop_decel_mps2: float = 3.0  # a firm, not an emergency, stop
    stop_hold_s: float = 5.0  # standing still before it drives on
    min_spawn_gap_m: float = 3.0  # spawns are continuous in metres: bumper-to-bumper gaps down to this


@dataclass(frozen=True, slots=True)
class NoiseSpec:
    """The noisy sensor model: Gaussian range noise and missed detections, each reading independently.

    Assumed values to be swept, not a sensor's datasheet: 0.5 m is the order of an automotive
    radar's range accuracy at 100 m; 1% of readings missed. A radar reads each vehicle's range
    rate too (Doppler): its sd is the speed accuracy of the radar class whose range accuracy the
    0.5 m stands for (Autoliv's 24 GHz radar, lane-change-assist mode, 4-80 m: range +-50 cm,
    speed +-2 km/h; its user manual, section 3.1), taken as the sd the way the range's is.
    """

    range_sd_m: float = 0.5
    miss_rate: float = 0.01
    range_rate_sd_mps: float = 2 / 3.6


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

    @property
    def control_dt_s(self) -> float:
        """One control step: the controller reads and commands once per this many seconds."""
        return self.physics_dt_s * self.control_every_steps

    @property
    def plan_budget_s(self) -> float:
        """A decision's planning time, in simulated time, and the most it may take on the machine: one control step.
        The controller acts once per control step, so a plan made from a snapshot acts at the next step at the
        earliest; the world moves on meanwhile (``spec.assumptions.Bounds.latency_s``). A plan that took longer on
        the machine than this broke the assumption (the audit counts it)."""
        return self.control_dt_s


ROAD, CAR, SENSORS, TRAFFIC, LOOP = RoadSpec(), CarSpec(), SensorSpec(), TrafficSpec(), LoopSpec()
SPEEDS, IDM, EVENTS, NOISE = SpeedSpec(), IdmSpec(), EventSpec(), NoiseSpec()

#: The highest stop rate that means anything: a stop starts at most once per vehicle per control step (a chance of 1).
MAX_STOP_RATE_PER_H = 3600 / LOOP.control_dt_s
