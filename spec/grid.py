"""The grid as a value: cell length, common speed, the AV's cell and the sensed window, and what they imply.

Every discrete number an engine uses (an action's left-lane shift and oncoming ticks, a
model's danger radius in cells, the AV's cell, the window) is derived here from physical
quantities: actions keep their speed and duration (``spec.actions``), the danger zone is a
distance (``spec.models``), and the window is a stretch of road. The paper's grid is 21 m
cells at 7 m/s; finer grids (10.5, 7, 5.25 m) are the same road and the same actions cut
finer. A cell length for which any of these is not a whole number of cells is bad input.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from functools import cached_property

from spec.actions import ACTION_RULES, Action
from spec.errors import OptionError

#: The paper's cell: the distance covered in one time unit (3 s) at the common speed.
PAPER_CELL_M = Fraction(21)
#: The common speed of the AV and of every other vehicle the model assumes (the paper's), m/s.
COMMON_SPEED_MPS = Fraction(7)
#: Road sensed behind the AV (the paper's 10 cells) and the whole sensed window (its cells 0..50).
BEHIND_M = Fraction(210)
WINDOW_M = Fraction(1050)
#: The most cells a window may have: every engine counts a lane's vehicles in a byte (Promela's ``byte nl``).
MAX_ROAD_CELLS = 254
#: Cell lengths the audit and the benchmarks sweep (the paper's and three finer ones).
STANDARD_CELLS_M: tuple[Fraction, ...] = (Fraction(21), Fraction(21, 2), Fraction(7), Fraction(21, 4))


@dataclass(frozen=True)
class Grid:
    """A discretisation of the road: every discrete effect is derived from it, never written down."""

    cell_m: Fraction = PAPER_CELL_M
    speed_mps: Fraction = COMMON_SPEED_MPS

    def __post_init__(self) -> None:
        """Reject a grid that cannot derive whole numbers of cells for every rule."""
        if not isinstance(self.cell_m, Fraction):
            object.__setattr__(self, "cell_m", as_fraction(self.cell_m, "--cell-m"))
        if self.cell_m <= 0 or self.speed_mps <= 0:
            raise OptionError("--cell-m", float(self.cell_m), "must be a positive length in metres")
        for what, value in (("the AV's cell", BEHIND_M / self.cell_m), ("the sensed window", WINDOW_M / self.cell_m)):
            _whole(value, self.cell_m, what)
        if WINDOW_M / self.cell_m > MAX_ROAD_CELLS:
            finest = float(WINDOW_M / MAX_ROAD_CELLS)
            raise OptionError("--cell-m", float(self.cell_m), f"too fine: the {float(WINDOW_M):g} m window would have "
                              f"more than {MAX_ROAD_CELLS} cells (the finest is {finest:.2f} m)")
        for action, rule in ACTION_RULES.items():
            units = rule.duration_s / self.time_unit_s
            _whole(units, self.cell_m, f"{action.value}'s duration ({rule.duration_s} s)", "time units")
            _whole(units * (1 - rule.speed_factor), self.cell_m, f"{action.value}'s left-lane shift")
            _whole(units * (1 + rule.speed_factor), self.cell_m, f"{action.value}'s oncoming ticks")
        object.__setattr__(self, "_hash", hash((self.cell_m, self.speed_mps)))

    def __hash__(self) -> int:
        """Hashed once: a grid keys the rules' caches on every step, and hashing its fractions each time is slow."""
        return self._hash  # type: ignore[attr-defined]

    # -- the grid's own numbers ----------------------------------------------------------------
    @property
    def cell(self) -> float:
        """The cell length in metres, as a float (for physics)."""
        return float(self.cell_m)

    @property
    def speed(self) -> float:
        """The common speed in m/s, as a float (for physics)."""
        return float(self.speed_mps)

    @property
    def time_unit_s(self) -> Fraction:
        """One cell at the common speed, in seconds."""
        return self.cell_m / self.speed_mps

    @cached_property
    def av_cell(self) -> int:
        """The cell the AV always sits at; cells grow in its direction of travel."""
        return int(BEHIND_M / self.cell_m)

    @cached_property
    def road_cells(self) -> int:
        """A scenario places vehicles in cells ``0 .. road_cells``."""
        return int(WINDOW_M / self.cell_m)

    @property
    def is_paper(self) -> bool:
        """Whether this is the paper's 21 m grid."""
        return self.cell_m == PAPER_CELL_M and self.speed_mps == COMMON_SPEED_MPS

    # -- derived effects (computed once per grid: engines read them in their inner loops) ---------
    @cached_property
    def _effects(self) -> dict[Action, tuple[int, int, int]]:
        """Per action: (time units, left-lane shift, oncoming ticks)."""
        out = {}
        for action, rule in ACTION_RULES.items():
            units = rule.duration_s / self.time_unit_s
            out[action] = (int(units), int(units * (1 - rule.speed_factor)), int(units * (1 + rule.speed_factor)))
        return out

    def units(self, action: Action) -> int:
        """An action's duration in time units."""
        return self._effects[action][0]

    def left_shift(self, action: Action) -> int:
        """How far every left-lane vehicle moves relative to the AV during ``action`` (negative: closer)."""
        return self._effects[action][1]

    def ticks(self, action: Action) -> int:
        """How many one-cell steps every oncoming vehicle makes towards the AV during ``action``."""
        return self._effects[action][2]

    @cached_property
    def max_ticks(self) -> int:
        """The most oncoming ticks of any action."""
        return max(self.ticks(a) for a in Action)

    @cached_property
    def _cells(self) -> dict[Fraction, int]:
        return {}

    def cells(self, distance_m: Fraction, what: str) -> int:
        """A distance that must be a whole number of cells (a danger zone), in cells."""
        known = self._cells.get(distance_m)
        if known is None:
            known = self._cells[distance_m] = _whole(distance_m / self.cell_m, self.cell_m, what)
        return known

    def to_json(self) -> float:
        """The grid as scenario files and records write it: the cell length in metres."""
        return float(self.cell_m)

    def describe(self) -> str:
        return f"{float(self.cell_m):g} m cells"


def as_fraction(value: object, option: str) -> Fraction:
    """A finite positive number (int, float, or decimal text) as an exact fraction; else bad input."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str, Fraction)):
        raise OptionError(option, value, "must be a number of metres")
    if isinstance(value, float) and not math.isfinite(value):
        raise OptionError(option, value, "must be a finite number of metres")
    try:
        number = Fraction(str(value)) if isinstance(value, float) else Fraction(value)
    except (ValueError, ZeroDivisionError):
        raise OptionError(option, value, "must be a number of metres") from None
    if number <= 0:
        raise OptionError(option, value, "must be a positive length in metres")
    return number


def _whole(value: Fraction, cell_m: Fraction, what: str, unit: str = "cells") -> int:
    if value.denominator != 1:
        raise OptionError("--cell-m", float(cell_m),
                          f"{what} is {float(value):g} {unit}, not a whole number (try 21, 10.5, 7 or 5.25)")
    return int(value)


#: The paper's grid: 21 m cells at 7 m/s, the AV at cell 10, the window 0..50.
PAPER_GRID = Grid()


def grid_for(cell_m: object = None) -> Grid:
    """The grid of a cell length (None: the paper's)."""
    if cell_m is None:
        return PAPER_GRID
    grid = Grid(as_fraction(cell_m, "--cell-m"))
    return PAPER_GRID if grid.is_paper else grid
