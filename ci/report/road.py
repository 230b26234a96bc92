"""A reproducer's traces drawn as the road: per engine run, a row per step with both lanes and every vehicle's cell,
the step where the run parts from the interpreter's replay of its own plan marked."""

from __future__ import annotations

from html import escape
from pathlib import Path

from ci.conformance.properties import PROPERTIES, PropertyName, first_difference
from ci.report.document import Drawing
from oracle.planner import solve
from oracle.planner import verdict_for as validate
from spec.answers import Limits, Status
from spec.errors import SuiteError
from spec.files import load_scenario
from spec.scenario import Scenario, problem_for
from spec.state import Lane, State

TIMEOUT_S = 10.0  # per engine run, as crossval's default
ROW_PX, LANE_PX, LABEL_PX, WIDTH_PX = 22, 9, 150, 960
COLOURS = {"av": "#1a9850", "same": "#2c7bb6", "oncoming": "#d7191c", "road": "#e0e0e0", "differ": "#ff7f00"}


def reproducer_drawing(scenario_file: Path, name: str, prop: str) -> Drawing | None:
    """The drawing of the runs ``prop`` reads on the scenario in ``scenario_file``; None when the file is gone."""
    if not scenario_file.is_file():
        return None
    try:
        scenario = load_scenario(scenario_file)
        keys = PROPERTIES[PropertyName(prop)].runs
    except (SuiteError, ValueError, KeyError):
        return None
    blocks: list[tuple[str, str, list[tuple[str, State]], int | None]] = []
    for key in keys:
        try:
            answer = solve(scenario, key.strategy, engine=key.engine, limits=Limits(timeout_s=TIMEOUT_S))
        except SuiteError as error:
            blocks.append((key.label, f"engine error: {error}", [], None))
            continue
        if answer.status is not Status.PLAN or answer.model is None:
            blocks.append((key.label, answer.status.value, [], None))
            continue
        replay = validate(problem_for(scenario, answer.model), answer.actions)
        states = list(answer.states or replay.states)
        differ = first_difference(replay.states, states) if answer.states else None
        actions = ["(start)"] + [a.value for a in answer.actions]
        blocks.append((key.label, f"{len(answer.actions)} actions" + ("" if replay.valid else
                                                                        f" (invalid: {replay.reason})"),
                       list(zip(actions, states, strict=False)), differ))
    return Drawing(name, _svg(scenario, blocks), f"{prop}: each engine run's states as the road (oncoming lane above, "
                                                 "the AV's direction to the right; green the AV, blue same-direction "
                                                 "vehicles, red oncoming; orange: where the run parts from the "
                                                 "interpreter's replay of its plan)")


def _svg(scenario: Scenario, blocks: list[tuple[str, str, list[tuple[str, State]], int | None]]) -> str:
    cells = scenario.grid.road_cells + 1
    cell_px = (WIDTH_PX - LABEL_PX) / cells
    parts: list[str] = []
    y = 0.0

    def rect(x: float, top: float, w: float, h: float, fill: str, extra: str = "") -> None:
        parts.append(f'<rect x="{x:.1f}" y="{top:.1f}" width="{w:.1f}" height="{h:.1f}" fill="{fill}"{extra}/>')

    def text(x: float, top: float, words: str, weight: str = "normal") -> None:
        parts.append(f'<text x="{x:.1f}" y="{top:.1f}" font-size="11" font-family="sans-serif" '
                     f'font-weight="{weight}">{escape(words)}</text>')

    for label, status, rows, differ in blocks:
        y += 16
        text(0, y, f"{label}: {status}", "bold")
        y += 6
        for n, (action, state) in enumerate(rows):
            top = y + n * ROW_PX
            text(0, top + 14, f"{n:>2} {action}")
            rect(LABEL_PX, top + 1, cells * cell_px, LANE_PX, COLOURS["road"])
            rect(LABEL_PX, top + 2 + LANE_PX, cells * cell_px, LANE_PX, COLOURS["road"])
            for cell in state.right_lane:
                if 0 <= cell < cells:
                    rect(LABEL_PX + cell * cell_px, top + 1, cell_px, LANE_PX, COLOURS["oncoming"])
            for cell in state.left_lane:
                if 0 <= cell < cells:
                    rect(LABEL_PX + cell * cell_px, top + 2 + LANE_PX, cell_px, LANE_PX, COLOURS["same"])
            av_top = top + 1 if state.lane is Lane.RIGHT else top + 2 + LANE_PX
            rect(LABEL_PX + scenario.grid.av_cell * cell_px, av_top, cell_px, LANE_PX, COLOURS["av"])
            if differ == n:
                rect(LABEL_PX - 2, top, cells * cell_px + 4, 2 * LANE_PX + 3, "none",
                     f' stroke="{COLOURS["differ"]}" stroke-width="2"')
        y += len(rows) * ROW_PX + 4
    height = y + 8
    return (f'<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH_PX}" height="{height:.0f}" '
            f'viewBox="0 0 {WIDTH_PX} {height:.0f}" role="img">' + "".join(parts) + "</svg>")
