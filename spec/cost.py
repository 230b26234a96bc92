"""The cost the ``optimal`` strategy minimises: its terms, most important first, and what one action adds to each.

One declaration that the Z3 encoding (``oracle.bmc``) translates into an objective and the conformance checker
(``ci.conformance.properties``) computes on its own, so an engine that orders or counts the terms differently is caught.
"""

from __future__ import annotations

from collections.abc import Iterable
from functools import cache

from spec.actions import ACTION_RULES, Action
from spec.lanes import Lane
from spec.state import State

#: The terms, most important first: the order is lexicographic.
COST_TERMS = ("lane_changes", "right_lane_steps", "brakes", "length")
COST_DOC = ("lexicographic: lane changes, then actions that end in the right lane, then brakes, "
            "then plan length; over every plan of at most `horizon` actions")


def step_cost(action: Action, after: State) -> tuple[int, ...]:
    """What one action, ending in ``after``, adds to each term, in ``COST_TERMS`` order."""
    return action_cost(action, after.lane)


@cache
def action_cost(action: Action, lane_after: Lane) -> tuple[int, ...]:
    """What one action that leaves the AV in ``lane_after`` adds to each term, in ``COST_TERMS`` order."""
    added = {"lane_changes": int(ACTION_RULES[action].changes_lane), "right_lane_steps": int(lane_after is Lane.RIGHT),
             "brakes": int(action is Action.BRAKE), "length": 1}
    return tuple(added[name] for name in COST_TERMS)


def total_cost(steps: Iterable[tuple[Action, State]]) -> tuple[int, ...]:
    """A plan's cost: each action with the state it ends in, summed term by term (``COST_TERMS`` order)."""
    total = [0] * len(COST_TERMS)
    for action, after in steps:
        for term, added in enumerate(step_cost(action, after)):
            total[term] += added
    return tuple(total)
