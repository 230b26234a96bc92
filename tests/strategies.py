"""Hypothesis strategies for valid scenarios."""

from __future__ import annotations

from hypothesis import strategies as st

from spec.constants import AV_CELL, ROAD_CELLS
from spec.lanes import Lane
from spec.scenario import Scenario, make_scenario


@st.composite
def scenarios(draw: st.DrawFn, max_left: int = 5, max_right: int = 2, horizon: int | None = None,
              span: int = ROAD_CELLS) -> Scenario:
    """A valid scenario: cells drawn near the AV so that plans and dead ends both occur."""
    lane = draw(st.sampled_from(list(Lane)))
    cells = st.integers(0, span)
    left = draw(st.lists(cells, max_size=max_left, unique=True))
    right = draw(st.lists(cells, max_size=max_right, unique=True))
    if lane is Lane.LEFT:
        left = [c for c in left if c != AV_CELL]
    else:
        right = [c for c in right if c != AV_CELL]
    ahead = sum(1 for c in left if c >= AV_CELL)
    targets = draw(st.integers(0, min(ahead, 3)))
    h = horizon if horizon is not None else draw(st.integers(0, 12))
    return make_scenario(lane, left, right, targets, horizon=h)
