"""Scenarios (a discretised sensor snapshot) and planning problems (a scenario under one model)."""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import TypeVar

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
from spec.sound import Sound
from spec.state import State

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
