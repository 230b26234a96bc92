"""ASCII drawings of both lanes, for people reading a plan."""

from __future__ import annotations

from spec.grid import Grid
from spec.lanes import Lane
from spec.state import State

#: What each mark of a drawing means, for a legend under it.
LEGEND = ("A the AV, T a target, v another left-lane vehicle, o an oncoming vehicle, X a vehicle in the AV's cell; "
          "n< >n: vehicles outside the window; travel to the right")


#: A drawing's marks by precedence: where one character stands for several cells, it shows the first it holds.
PRECEDENCE = "XATvo."
#: Characters around a lane's cells in a drawing: its name, the counts outside the window, the spaces between.
FRAME_CHARS = 16


def cells_per_char(grid: Grid, max_chars: int | None) -> int:
    """How many cells one character of a drawing stands for: 1, or the fewest that fit the road in ``max_chars``."""
    width = grid.road_cells + 1
    return 1 if max_chars is None or width <= max_chars else -(-width // max(1, max_chars))


def draw(state: State, grid: Grid, targets: tuple[int, ...] = (), max_chars: int | None = None) -> list[str]:
    """Two lines, travel direction to the right: the left lane on top, oncoming below.

    ``A`` the AV, ``T`` a target, ``v`` another left-lane vehicle, ``o`` an oncoming one,
    ``X`` a vehicle in the AV's cell. Cells outside the window are counted at the edges. With ``max_chars``, a road
    longer than that is drawn with one character for several cells (``cells_per_char``), each showing the mark of
    highest ``PRECEDENCE`` among its cells.
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
    step = cells_per_char(grid, max_chars)
    drawn = {lane: "".join(min(cells[i:i + step], key=PRECEDENCE.index) for i in range(0, width, step))
             for lane, cells in rows.items()}
    return [f"{lane.value:>5} {outside[lane][0]:>2}< {drawn[lane]} >{outside[lane][1]:<2}" for lane in Lane]
