"""Scenarios (a discretised sensor snapshot) and planning problems (a scenario under one model)."""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, replace
from typing import TypeVar

from spec.cells import left_extent_m, oncoming_extent_m
from spec.constants import DEFAULT_HORIZON, MAX_HORIZON
from spec.errors import BadInput, ScenarioError
from spec.grid import PAPER_GRID, Grid, grid_for
from spec.lanes import Lane
from spec.models import (
    GOAL_RULES,
    MODEL_RULES,
    GoalRule,
    ModelChoice,
    ModelKind,
    ModelRules,
    goal_kind,
    models_for,
)
from spec.rules import collision_in, collision_span
from spec.sound import Extent, Sound
from spec.state import State
from spec.tracking import Speed

E = TypeVar("E", bound=enum.Enum)


@dataclass(frozen=True, slots=True)
class Scenario:
    """A validated scenario: construct through ``make_scenario`` or a file loader."""

    lane: Lane
    left_lane: tuple[int, ...]
    right_lane: tuple[int, ...]
    targets: int = 0
    model: ModelChoice = ModelChoice.AUTO
    horizon: int = DEFAULT_HORIZON
    grid: Grid = PAPER_GRID
    sound: Sound | None = None  # None: the paper's rules; else the sound model under these assumptions
    #: Where each vehicle's centre was sensed, metres ahead of the AV before the sensing error, per vehicle of its
    #: lane in order (``sensed``); None: anywhere in its cell. Only the sound model reads them (``spec.sound``).
    left_m: tuple[Extent, ...] | None = None
    right_m: tuple[Extent, ...] | None = None
    #: Each vehicle's speed interval at the snapshot, m/s along its direction of travel, per vehicle of its lane in
    #: order (``measured_speeds``); None: its lane's speeds. The sound model moves a measured vehicle by its own
    #: dynamics (``spec.dynamics``): it may brake to a standstill at any instant.
    left_mps: tuple[Speed, ...] | None = None
    right_mps: tuple[Speed, ...] | None = None

    @property
    def target_indices(self) -> tuple[int, ...]:
        """Indices into ``left_lane`` of the targets: the nearest vehicles at or ahead of the AV."""
        ahead = [i for i, cell in enumerate(self.left_lane) if cell >= self.grid.av_cell]
        return tuple(ahead[: self.targets])

    def initial_state(self) -> State:
        """The state the AV starts in."""
        return State(self.lane, self.left_lane, self.right_lane)


@dataclass(frozen=True, slots=True)
class Problem:
    """One model applied to one scenario: what every engine is asked to solve."""

    scenario: Scenario
    rules: ModelRules
    goal: GoalRule
    horizon: int

    @property
    def model(self) -> ModelKind:
        """The model this problem uses."""
        return self.rules.kind

    @property
    def grid(self) -> Grid:
        """The grid the scenario's cells are on."""
        return self.scenario.grid


def problem_for(scenario: Scenario, model: ModelKind, horizon: int | None = None) -> Problem:
    """The planning problem of ``scenario`` under ``model``."""
    goal = GOAL_RULES[goal_kind(model, scenario.lane)]
    return Problem(scenario, MODEL_RULES[model], goal, scenario.horizon if horizon is None else horizon)


def make_scenario(
    lane: Lane | str,
    left_lane: object,
    right_lane: object,
    targets: object = 0,
    model: ModelChoice | str = ModelChoice.AUTO,
    horizon: object = DEFAULT_HORIZON,
    cell_m: object = None,
    grid: Grid | None = None,
) -> Scenario:
    """A validated scenario on ``grid`` (or the grid of ``cell_m``; default the paper's); raises ScenarioError
    naming the key, value and reason."""
    if grid is None:
        try:
            grid = grid_for(cell_m)
        except BadInput as err:
            raise ScenarioError("cell_m", cell_m, err.reason) from None
    lane_v = _check_enum(Lane, "lane", lane)
    model_v = _check_enum(ModelChoice, "model", model)
    left = _check_cells("left_lane", left_lane, grid)
    right = _check_cells("right_lane", right_lane, grid)
    targets_v = _check_int("targets", targets, 0, grid.road_cells + 1)
    horizon_v = _check_int("horizon", horizon, 0, MAX_HORIZON)
    scenario = Scenario(lane_v, tuple(sorted(left)), tuple(sorted(right)), targets_v, model_v, horizon_v, grid)
    _check_targets(scenario)
    _check_no_initial_collision(scenario, left, right)
    return scenario


def refined(scenario: Scenario, grid: Grid) -> Scenario:
    """The same scenario on a finer ``grid`` whose cells divide the scenario's: every vehicle at the same distance
    from the AV, the same targets and horizon (the same traffic, cut finer)."""
    ratio = scenario.grid.cell_m / grid.cell_m
    if ratio.denominator != 1:
        raise ValueError(f"{grid.describe()} does not divide {scenario.grid.describe()}")
    k, av = int(ratio), scenario.grid.av_cell

    def move(cells: tuple[int, ...]) -> list[int]:
        return [grid.av_cell + (c - av) * k for c in cells]

    finer = make_scenario(scenario.lane, move(scenario.left_lane), move(scenario.right_lane), scenario.targets,
                          scenario.model, scenario.horizon, grid=grid)
    return replace(finer, left_mps=scenario.left_mps, right_mps=scenario.right_mps)


def sensed(scenario: Scenario, left_m: object = None, right_m: object = None) -> Scenario:
    """``scenario`` with what its snapshot measured: per vehicle of a lane (in its cells' order) an interval
    ``[lo, hi]`` of metres ahead of the AV where its centre was (a reading: ``[dx, dx]``; a kept track: its
    interval), finite, ``lo <= hi``, and touching its cell's extent (the cell is where the same vehicle was put);
    None leaves a lane's vehicles anywhere in their cells. Bad input raises ScenarioError naming ``left_m[i]``."""
    out: dict[str, tuple[Extent, ...] | None] = {}
    for key, value, cells, extent in (
            ("left_m", left_m, scenario.left_lane, lambda c: left_extent_m(c, scenario.lane, scenario.grid)),
            ("right_m", right_m, scenario.right_lane, lambda c: oncoming_extent_m(c, scenario.grid))):
        if value is None:
            out[key] = None
            continue
        if not isinstance(value, (list, tuple)) or len(value) != len(cells):
            raise ScenarioError(key, value, f"must be a list of {len(cells)} [lo, hi] intervals, one per vehicle")
        intervals = []
        for i, (cell, pair) in enumerate(zip(cells, value, strict=True)):
            where = f"{key}[{i}]"
            if not isinstance(pair, (list, tuple)) or len(pair) != 2 or not all(
                    isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in pair):
                raise ScenarioError(where, pair, "must be two finite numbers [lo, hi] (metres ahead of the AV)")
            lo, hi = float(pair[0]), float(pair[1])
            c_lo, c_hi = extent(cell)
            if lo > hi:
                raise ScenarioError(where, pair, "the lower end is above the upper end")
            if hi < c_lo or lo > c_hi:
                raise ScenarioError(where, pair, f"outside its cell {cell}'s extent {c_lo:g}..{c_hi:g} m")
            intervals.append((lo, hi))
        out[key] = tuple(intervals)
    return replace(scenario, left_m=out["left_m"], right_m=out["right_m"])


#: The fastest speed interval a scenario may state (m/s): above any road vehicle's (a typo, not a measurement).
MAX_MEASURED_MPS = 100.0


def measured_speeds(scenario: Scenario, left_mps: object = None, right_mps: object = None) -> Scenario:
    """``scenario`` with each vehicle's measured speed interval: per vehicle of a lane (in its cells' order) ``[lo,
    hi]`` in m/s along its direction of travel, ``0 <= lo <= hi <= MAX_MEASURED_MPS``; None leaves a lane's vehicles
    at their lane's speeds. Bad input raises ScenarioError naming ``left_mps[i]``."""
    out: dict[str, tuple[Speed, ...] | None] = {}
    for key, value, cells in (("left_mps", left_mps, scenario.left_lane), ("right_mps", right_mps,
                                                                          scenario.right_lane)):
        if value is None:
            out[key] = None
            continue
        lane = key.replace("_mps", "_lane")
        if not isinstance(value, (list, tuple)) or len(value) != len(cells):
            raise ScenarioError(key, value, f"must be a list of {len(cells)} [lo, hi] speed intervals, one per "
                                            f"vehicle of {lane}")
        speeds = []
        for i, pair in enumerate(value):
            where = f"{key}[{i}]"
            if not isinstance(pair, (list, tuple)) or len(pair) != 2 or not all(
                    isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in pair):
                raise ScenarioError(where, pair, "must be two finite numbers [lo, hi] (m/s along its direction)")
            lo, hi = float(pair[0]), float(pair[1])
            if lo < 0:
                raise ScenarioError(where, pair, "a speed below 0: no vehicle drives backwards")
            if lo > hi:
                raise ScenarioError(where, pair, "the lower end is above the upper end")
            if hi > MAX_MEASURED_MPS:
                raise ScenarioError(where, pair, f"above {MAX_MEASURED_MPS:g} m/s")
            speeds.append((lo, hi))
        out[key] = tuple(speeds)
    return replace(scenario, left_mps=out["left_mps"], right_mps=out["right_mps"])


def _check_enum(kind: type[E], key: str, value: object) -> E:
    if isinstance(value, kind):
        return value
    allowed = [m.value for m in kind]
    if not isinstance(value, str) or value not in allowed:
        raise ScenarioError(key, value, f"must be one of {', '.join(map(repr, allowed))}")
    return kind(value)


def _check_int(key: str, value: object, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ScenarioError(key, value, "must be an integer")
    if not low <= value <= high:
        raise ScenarioError(key, value, f"must be between {low} and {high}")
    return value


def _check_cells(key: str, value: object, grid: Grid) -> list[int]:
    if not isinstance(value, (list, tuple)):
        raise ScenarioError(key, value, "must be a list of cells")
    seen: dict[int, int] = {}
    for i, cell in enumerate(value):
        where = f"{key}[{i}]"
        if isinstance(cell, bool) or not isinstance(cell, int):
            raise ScenarioError(where, cell, "a cell must be an integer")
        if not 0 <= cell <= grid.road_cells:
            raise ScenarioError(where, cell, f"cell outside the sensed window 0..{grid.road_cells}")
        if cell in seen:
            raise ScenarioError(where, cell, f"two vehicles in one cell (also {key}[{seen[cell]}])")
        seen[cell] = i
    return list(value)


def _check_targets(scenario: Scenario) -> None:
    av_cell = scenario.grid.av_cell
    ahead = sum(1 for cell in scenario.left_lane if cell >= av_cell)
    if scenario.targets > ahead:
        raise ScenarioError(
            "targets", scenario.targets, f"only {ahead} left-lane vehicle(s) at or ahead of the AV (cell {av_cell})"
        )


def _check_no_initial_collision(scenario: Scenario, left: list[int], right: list[int]) -> None:
    """Reject a start that collides under every model the scenario may use; name the vehicle as the file does."""
    start, models = scenario.initial_state(), models_for(scenario.model)
    if not all(collision_in(start, MODEL_RULES[m], scenario.grid, 0) for m in models):
        return
    narrowest = min(models, key=lambda m: MODEL_RULES[m].danger_m)  # collides under every model: under this one
    lo, hi = collision_span(scenario.lane, MODEL_RULES[narrowest], scenario.grid)
    given = left if scenario.lane is Lane.LEFT else right
    i = next(k for k, cell in enumerate(given) if lo <= cell <= hi)
    what = ("vehicle in the AV's cell" if scenario.lane is Lane.LEFT
            else f"oncoming vehicle within {(hi - lo) // 2} cell(s) of the AV")
    raise ScenarioError(f"{scenario.lane.value}_lane[{i}]", given[i], f"initial collision: {what}")
