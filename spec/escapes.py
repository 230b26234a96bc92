"""The sound model commits only to what it can undo: committed actions, a proved escape, a predicted continuation.

An answer of the sound model under a ``Commitment`` (the commitment semantics; ``Sound.commitment`` None is the
whole-plan semantics, every plan proved to its end) has three parts:

- **committed**: the actions up to the next decision, each safe at every instant for every motion inside the
  assumptions, as a plan's steps are (``spec.sound``);
- **escape**: a declared manoeuvre (``ESCAPES``) from where the committed actions end, proved with them: its steps
  as safe, and its end safe for ever under the minimal-risk manoeuvre (``spec.envelope.MinimalRisk``), as a plan's
  last state is ("no blind moments"). None when the committed actions are a whole proved plan (the goal for every
  position, then safe for ever): the escape is never needed;
- **predicted**: a continuation from there to the goal under nominal motion on the grid: the paper's rules
  (``spec.rules``) from the snapshot's cells, every vehicle at the common speed, no phantoms, the paper's collisions
  and goals; the whole answer (committed and predicted actions) is one plan of the paper's rules whose first action
  the sound model commits to. A prediction, never a safety claim: it picks which of the steps the sound model
  proves leads towards the goal.

The safety claim: while every assumption holds and the AV decides at least once per committed part, it always
executes a proved committed part or the rest of the last proved one and its escape, every instant of which was proved
safe against every motion inside the assumptions, phantoms included; so it never breaks the safety specification.
Phantoms bound the escape, not the whole manoeuvre: the unseen road beyond the sensors moves with the AV, and a
vehicle that comes out of it is seen at the next decision, whose escape is proved against it.

Escapes keep the lane guard of their actions (a lane change from the lane it leaves) but not a model's count of
lane changes: a way back into the AV's own lane is never a move towards the goal.

A start that already breaks the specification is no plan (``spec.answers.Status.UNSAFE_START``): the answer names
the violation and the escape to take at once, the lane's first (``unsafe_start_escape``).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from spec.actions import ACTION_RULES, Action
from spec.constants import MAX_HORIZON
from spec.envelope import MINIMAL_RISK
from spec.errors import OptionError, parse_choice
from spec.lanes import Lane


class EscapeKind(enum.Enum):
    """What an escape does."""

    MINIMAL_RISK = "minimal_risk"  # in the left lane: brake in lane to the hold speed (``MinimalRisk``)
    ABORT = "abort"  # from the right lane: back into the left lane, behind the vehicles being overtaken
    COMPLETE = "complete"  # from the right lane: on past them, then back into the left lane


class Semantics(enum.Enum):
    """How the sound model answers: whole proved plans, or commitments with a proved escape."""

    COMMIT = "commit"
    WHOLE = "whole"


@dataclass(frozen=True, slots=True)
class Escape:
    """One escape manoeuvre: from a lane, its actions (then the minimal-risk manoeuvre for ever)."""

    kind: EscapeKind
    from_lane: Lane
    actions: tuple[Action, ...]
    why: str

    def describe(self) -> str:
        steps = ", ".join(a.value for a in self.actions)
        return f"{self.kind.value} ({steps + ', then ' if steps else ''}the minimal-risk manoeuvre: {self.why})"


#: Every escape, in the order they are tried (the first proved is the answer's): from the left lane the
#: minimal-risk manoeuvre, at once or after a slower action in lane (whose ramp, centred on the boundary as the
#: executor joins actions, starts before it: what makes a fast step provable); from the right lane the shortest ways
#: back first.
ESCAPES: tuple[Escape, ...] = (
    Escape(EscapeKind.MINIMAL_RISK, Lane.LEFT, (), "brake in lane to the slowest speed ahead"),
    Escape(EscapeKind.MINIMAL_RISK, Lane.LEFT, (Action.DRIVE,), "slow to the common speed in lane first"),
    Escape(EscapeKind.MINIMAL_RISK, Lane.LEFT, (Action.BRAKE,), "slow to half the common speed in lane first"),
    Escape(EscapeKind.ABORT, Lane.RIGHT, (Action.LEFT_LANE_CHANGE,), "back into the left lane at once"),
    Escape(EscapeKind.COMPLETE, Lane.RIGHT, (Action.ACCELERATE, Action.LEFT_LANE_CHANGE),
           "speed past, then back into the left lane"),
    Escape(EscapeKind.ABORT, Lane.RIGHT, (Action.BRAKE, Action.LEFT_LANE_CHANGE),
           "drop back, then back into the left lane behind"),
    Escape(EscapeKind.COMPLETE, Lane.RIGHT, (Action.ACCELERATE, Action.ACCELERATE, Action.LEFT_LANE_CHANGE),
           "speed past for longer, then back into the left lane"),
)


def check_escapes(escapes: tuple[Escape, ...]) -> tuple[Escape, ...]:
    """The registry checks itself: every escape's actions are enabled lane by lane from its lane and end in the left
    lane (where the minimal-risk manoeuvre holds for ever); a minimal-risk escape stays in the left lane and never
    speeds up, and only it may have no actions; an abort never speeds up, a completion does; no two are the same."""
    for e in escapes:
        lane = e.from_lane
        for a in e.actions:
            rule = ACTION_RULES[a]
            if rule.from_lane not in (None, lane):
                raise ValueError(f"escape {e.describe()}: {a.value} is not enabled from the {lane.value} lane")
            lane = rule.to_lane or lane
        if lane is not Lane.LEFT:
            raise ValueError(f"escape {e.describe()} ends in the {lane.value} lane")
        if e.kind is EscapeKind.MINIMAL_RISK and (e.from_lane is not Lane.LEFT or any(
                a not in (Action.DRIVE, Action.BRAKE) for a in e.actions)):
            raise ValueError(f"escape {e.describe()}: the minimal-risk manoeuvre stays in the left lane, never faster")
        if e.kind is not EscapeKind.MINIMAL_RISK and not e.actions:
            raise ValueError(f"escape {e.describe()}: only the minimal-risk manoeuvre has no actions")
        if (Action.ACCELERATE in e.actions) != (e.kind is EscapeKind.COMPLETE):
            raise ValueError(f"escape {e.describe()}: a completion speeds up, an abort never does")
    if len({(e.from_lane, e.actions) for e in escapes}) != len(escapes):
        raise ValueError("two escapes are the same manoeuvre")
    return escapes


check_escapes(ESCAPES)


def unsafe_start_escape(lane: Lane) -> Escape:
    """What the AV does from a start that already breaks the specification: the lane's first escape. In the left
    lane every conflict a start can break is with a vehicle in the AV's own lane, and braking in lane opens every gap
    ahead from the first instant; in the right lane leaving it at once ends every oncoming conflict soonest. Nothing
    is proved from such a start."""
    return next(e for e in ESCAPES if e.from_lane is lane)


class MoveWay(enum.Enum):
    """How a decision taken during a lane change's sideways move (a breach sensed during it) may take the move."""

    FINISH = "finish"  # on into the lane it goes to, for what is left of it
    UNDO = "undo"  # back into the lane it left, on a cosine of the time it has taken (``MinimalRisk``'s move back)


def move_ways(to_lane: Lane, done_s: float, left_s: float) -> tuple[tuple[MoveWay, Lane, float], ...]:
    """The ways a decision taken ``done_s`` into a sideways move towards ``to_lane`` (``left_s`` left) proves, in the
    order they are tried, each with the lane its start is in and how long the move keeps the AV in both lanes from
    it (``spec.sound.Sound.sideways_s``): finishing it, then undoing it, only within ``MinimalRisk.reverse_within_s``
    (where the executor's move back is measured: from half-way a car at 3.5 m/s runs on into the other lane before
    it turns back)."""
    back = Lane.LEFT if to_lane is Lane.RIGHT else Lane.RIGHT
    ways = [(MoveWay.FINISH, to_lane, left_s)]
    if done_s <= MINIMAL_RISK.reverse_within_s + 1e-9:
        ways.append((MoveWay.UNDO, back, done_s))
    return tuple(ways)


ALL_KINDS = tuple(EscapeKind)


@dataclass(frozen=True, slots=True)
class Commitment:
    """The commitment semantics' parameters: the most actions one answer commits to (None: as many as are proved;
    the AV must decide again at least this often), and the escapes it may prove."""

    most_actions: int | None = None
    escapes: tuple[EscapeKind, ...] = ALL_KINDS

    def allowed(self, lane: Lane) -> tuple[Escape, ...]:
        """The escapes from ``lane`` this commitment may prove, in ``ESCAPES``' order."""
        return tuple(e for e in ESCAPES if e.from_lane is lane and e.kind in self.escapes)

    def describe(self) -> str:
        most = "as many actions as are proved" if self.most_actions is None else f"at most {self.most_actions}"
        kinds = ", ".join(k.value for k in self.escapes)
        return f"commits to {most}, escapes: {kinds}"


COMMIT = Commitment()


def parse_semantics(value: object, where: str) -> Semantics:
    return parse_choice(Semantics, value, where)


def parse_most_actions(value: object, where: str) -> int:
    """The most actions an answer commits to: a whole number from 1 to the largest horizon."""
    if isinstance(value, bool) or not isinstance(value, (int, str)):
        raise OptionError(where, value, f"must be a whole number from 1 to {MAX_HORIZON}")
    try:
        number = int(value)
    except ValueError:
        raise OptionError(where, value, f"must be a whole number from 1 to {MAX_HORIZON}") from None
    if not 1 <= number <= MAX_HORIZON:
        raise OptionError(where, value, f"must be a whole number from 1 to {MAX_HORIZON} (an answer commits to "
                                        "at least one action)")
    return number


def parse_escape_kinds(value: object, where: str) -> tuple[EscapeKind, ...]:
    """Escape kinds as options (``abort,complete``) and files (a list) write them: known, none twice, at least one."""
    names = value.split(",") if isinstance(value, str) else value
    if not isinstance(names, (list, tuple)) or not names:
        raise OptionError(where, value, f"must name at least one escape ({', '.join(k.value for k in EscapeKind)})")
    kinds: list[EscapeKind] = []
    for name in names:
        text = name.strip() if isinstance(name, str) else name
        if text not in [k.value for k in EscapeKind]:
            raise OptionError(where, value, f"unknown escape {text!r} (known: "
                                            f"{', '.join(k.value for k in EscapeKind)})")
        kind = EscapeKind(text)
        if kind in kinds:
            raise OptionError(where, value, f"escape {text!r} given twice")
        kinds.append(kind)
    return tuple(k for k in EscapeKind if k in kinds)
