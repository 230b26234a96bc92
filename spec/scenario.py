"""Scenarios (a discretised sensor snapshot), states, collisions, and planning problems."""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import TypeVar

from spec.constants import AV_CELL, DEFAULT_HORIZON, MAX_HORIZON, ROAD_CELLS
from spec.errors import ScenarioError
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

E = TypeVar("E", bound=enum.Enum)


@dataclass(frozen=True, slots=True)
class State:
    """One state of the transition system: cells are relative to the AV (at AV_CELL)."""

    lane: Lane
    left_lane: tuple[int, ...]  # same-direction vehicles, ascending; never clipped
    right_lane: tuple[int, ...]  # oncoming vehicles, ascending; never clipped
    lane_changes: int = 0
    steps: int = 0


@dataclass(frozen=True, slots=True)
class Collision:
    """A collision: the state it happened in and the vehicle hit."""

    state: State
    lane: Lane  # the lane of the vehicle hit
    vehicle: int  # its index in that lane's tuple (ascending cells)
    cell: int  # its cell when hit
    tick: int  # 0: right after the action's effect; k: after oncoming tick k

    def describe(self) -> str:
        """One line naming the vehicle, its cell, and when it was hit."""
        when = "after the effect" if self.tick == 0 else f"after oncoming tick {self.tick}"
        return f"collision with {self.lane.value}_lane[{self.vehicle}] at cell {self.cell} {when}"


@dataclass(frozen=True, slots=True)
class Scenario:
    """A validated scenario: construct through ``make_scenario`` or a file loader."""

    lane: Lane
    left_lane: tuple[int, ...]
    right_lane: tuple[int, ...]
    targets: int = 0
    model: ModelChoice = ModelChoice.AUTO
    horizon: int = DEFAULT_HORIZON

    @property
    def target_indices(self) -> tuple[int, ...]:
        """Indices into ``left_lane`` of the targets: the nearest vehicles at or ahead of the AV."""
        ahead = [i for i, cell in enumerate(self.left_lane) if cell >= AV_CELL]
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
) -> Scenario:
    """A validated scenario; raises ScenarioError naming the key, value and reason."""
    lane_v = _check_enum(Lane, "lane", lane)
    model_v = _check_enum(ModelChoice, "model", model)
    left = _check_cells("left_lane", left_lane)
    right = _check_cells("right_lane", right_lane)
    targets_v = _check_int("targets", targets, 0, ROAD_CELLS + 1)
    horizon_v = _check_int("horizon", horizon, 0, MAX_HORIZON)
    scenario = Scenario(lane_v, tuple(sorted(left)), tuple(sorted(right)), targets_v, model_v, horizon_v)
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


def _check_cells(key: str, value: object) -> list[int]:
    if not isinstance(value, (list, tuple)):
        raise ScenarioError(key, value, "must be a list of cells")
    seen: dict[int, int] = {}
    for i, cell in enumerate(value):
        where = f"{key}[{i}]"
        if isinstance(cell, bool) or not isinstance(cell, int):
            raise ScenarioError(where, cell, "a cell must be an integer")
        if not 0 <= cell <= ROAD_CELLS:
            raise ScenarioError(where, cell, f"cell outside the sensed window 0..{ROAD_CELLS}")
        if cell in seen:
            raise ScenarioError(where, cell, f"two vehicles in one cell (also {key}[{seen[cell]}])")
        seen[cell] = i
    return list(value)


def _check_targets(scenario: Scenario) -> None:
    ahead = sum(1 for cell in scenario.left_lane if cell >= AV_CELL)
    if scenario.targets > ahead:
        raise ScenarioError(
            "targets", scenario.targets, f"only {ahead} left-lane vehicle(s) at or ahead of the AV (cell {AV_CELL})"
        )


def _check_no_initial_collision(scenario: Scenario, left: list[int], right: list[int]) -> None:
    """Reject a start that collides under every model the scenario may use."""
    radius = min(MODEL_RULES[m].danger_radius for m in models_for(scenario.model))
    if scenario.lane is Lane.LEFT and AV_CELL in left:
        i = left.index(AV_CELL)
        raise ScenarioError(f"left_lane[{i}]", AV_CELL, "initial collision: vehicle in the AV's cell")
    if scenario.lane is Lane.RIGHT:
        for i, cell in enumerate(right):
            if abs(cell - AV_CELL) <= radius:
                raise ScenarioError(
                    f"right_lane[{i}]", cell, f"initial collision: oncoming vehicle within {radius} cell(s) of the AV"
                )
