"""ASCII drawings of both lanes, for people reading a plan."""

from __future__ import annotations

from spec.grid import Grid
from spec.lanes import Lane
from spec.state import State

#: What each mark of a drawing means, for a legend under it.
LEGEND = ("A the AV, T a target, v another left-lane vehicle, o an oncoming vehicle, X a vehicle in the AV's cell; "
          "n< >n: vehicles outside the window; travel to the right")


def draw(state: State, grid: Grid, targets: tuple[int, ...] = ()) -> list[str]:
    """Two lines, travel direction to the right: the left lane on top, oncoming below.

    ``A`` the AV, ``T`` a target, ``v`` another left-lane vehicle, ``o`` an oncoming one,
    ``X`` a vehicle in the AV's cell. Cells outside the window are counted at the edges.
    """
    width = grid.road_cells + 1
    rows = {Lane.LEFT: ["."] * width, Lane.RIGHT: ["."] * width}
    outside = {Lane.LEFT: [0, 0], Lane.RIGHT: [0, 0]}
    marks = [(Lane.LEFT, c, "T" if i in targets else "v") for i, c in enumerate(state.left_lane)]
    marks += [(Lane.RIGHT, c, "o") for c in state.right_lane]
    for lane, cell, mark in marks:
        if 0 <= cell < width:
            rows[lane][cell] = mark
        else:
            outside[lane][cell >= width] += 1
    here = rows[state.lane][grid.av_cell]
    rows[state.lane][grid.av_cell] = "A" if here == "." else "X"
    return [f"{lane.value:>5} {outside[lane][0]:>2}< {''.join(rows[lane])} >{outside[lane][1]:<2}" for lane in Lane]
