"""Golden files of the rendered Promela: a change to spec/ or the renderer shows up here first.

Regenerate after an intended change with UPDATE_GOLDEN=1 and review the diff.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from promela.render import Shape, render, render_for, scenario_values
from spec.library import builtin
from spec.models import GoalKind, ModelKind
from spec.scenario import problem_for

GOLDEN = Path(__file__).parent / "golden"
SHAPES = [Shape(ModelKind.FINAL, GoalKind.OVERTAKE), Shape(ModelKind.PREPARATIONS, GoalKind.RETURN_LEFT),
          Shape(ModelKind.PREPARATIONS, GoalKind.CLOSE_GAP)]


def check_golden(name: str, text: str) -> None:
    path = GOLDEN / name
    if os.environ.get("UPDATE_GOLDEN"):
        path.write_text(text)
    assert path.read_text() == text, f"{name} differs from its golden file (UPDATE_GOLDEN=1 to accept)"


@pytest.mark.parametrize("shape", SHAPES, ids=lambda s: f"{s.model.value}-{s.goal.value}")
def test_injected_model_golden(shape: Shape) -> None:
    check_golden(f"{shape.model.value}-{shape.goal.value}.pml", render(shape))


def test_literal_model_of_the_paper_example_golden() -> None:
    problem = problem_for(builtin("paper_example").load(), ModelKind.FINAL)  # type: ignore[union-attr]
    check_golden("paper_example-final.pml", render_for(problem))


def test_rendering_is_deterministic() -> None:
    assert render(SHAPES[0]) == render(SHAPES[0])


def test_scenario_values_line() -> None:
    problem = problem_for(builtin("prep_case_a").load(), ModelKind.PREPARATIONS)  # type: ignore[union-attr]
    assert scenario_values(problem) == "1 4 10 11 13 14 1 17 2 0 30"  # the vehicle alongside is FV1
