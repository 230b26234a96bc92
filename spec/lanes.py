"""The two lanes of the road."""

from __future__ import annotations

import enum


class Lane(enum.Enum):
    """A lane: the AV's own (left, same-direction traffic) or the oncoming one (right)."""

    LEFT = "left"
    RIGHT = "right"

    __hash__ = object.__hash__  # members are singletons: identity is equality, and Enum's own hash is slow Python

    @property
    def other(self) -> Lane:
        """The other lane."""
        return Lane.RIGHT if self is Lane.LEFT else Lane.LEFT
