"""Golden files of the rendered Promela: a change to spec/ or the renderer shows up here first.

Regenerate after an intended change with UPDATE_GOLDEN=1 and review the diff.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from promela.render import Query, Shape, render, render_for, scenario_values, standard_shape
from spec.actions import ACTION_ORDER, Action
from spec.grid import STANDARD_CELLS_M, Grid
from spec.library import builtin
from spec.models import GoalKind, ModelKind
from spec.scenario import problem_for

GOLDEN = Path(__file__).parent / "golden"
SHAPES = [standard_shape(ModelKind.FINAL, GoalKind.OVERTAKE),
          standard_shape(ModelKind.PREPARATIONS, GoalKind.RETURN_LEFT),
          standard_shape(ModelKind.PREPARATIONS, GoalKind.CLOSE_GAP)]


def check_golden(name: str, text: str) -> None:
    path = GOLDEN / name
    if os.environ.get("UPDATE_GOLDEN"):
        path.write_text(text)
    assert path.read_text() == text, f"{name} differs from its golden file (UPDATE_GOLDEN=1 to accept)"


@pytest.mark.parametrize("shape", SHAPES, ids=lambda s: s.name)
def test_injected_model_golden(shape: Shape) -> None:
    check_golden(f"{shape.name}.pml", render(shape))


def test_literal_model_of_the_paper_example_golden() -> None:
    problem = problem_for(builtin("paper_example").load(), ModelKind.FINAL)  # type: ignore[union-attr]
    check_golden("paper_example-final.pml", render_for(problem))


def test_rendering_is_the_same_in_another_process_with_another_hash_seed() -> None:
    """The verifier cache is keyed by the rendered text: it must not depend on set or dict order in one process."""
    code = ("from promela.render import render, standard_shape; from spec.models import GoalKind, ModelKind; "
            "from spec.grid import Grid; from fractions import Fraction; import sys; "
            "sys.stdout.write(render(standard_shape(ModelKind.FINAL, GoalKind.OVERTAKE, Grid(Fraction(7)))))")
    texts = {subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                            env={**os.environ, "PYTHONHASHSEED": seed}).stdout for seed in ("1", "2")}
    assert texts == {render(standard_shape(ModelKind.FINAL, GoalKind.OVERTAKE, Grid(7)))}


@pytest.mark.parametrize("cell_m", STANDARD_CELLS_M[1:], ids=lambda c: f"{float(c):g}m")
def test_a_finer_grid_renders_its_own_numbers(cell_m) -> None:
    grid = Grid(cell_m)
    text = render(standard_shape(ModelKind.FINAL, GoalKind.OVERTAKE, grid))
    assert f"#define AV_CELL {grid.av_cell}\n" in text and f"#define MAXL {grid.road_cells + 1}\n" in text
    assert f"#define DANGER {grid.av_cell // 10}\n" in text  # 21 m: one cell per 21 m of the grid's cell
    assert f"{float(cell_m):g} m cells" in text.splitlines()[0]


def test_scenario_values_line() -> None:
    problem = problem_for(builtin("prep_case_a").load(), ModelKind.PREPARATIONS)  # type: ignore[union-attr]
    assert scenario_values(problem) == "1 4 10 11 13 14 1 17 2 0 30 31 0"  # the vehicle alongside is FV1; any first
    drive_or_brake = Query(firsts=(Action.DRIVE, Action.BRAKE))  # action (31: the bit of each), none needed
    assert scenario_values(problem, drive_or_brake).endswith(
        f" 30 {(1 << ACTION_ORDER.index(Action.DRIVE)) | (1 << ACTION_ORDER.index(Action.BRAKE))} 1")
