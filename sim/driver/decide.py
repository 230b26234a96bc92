"""What a decision does with its planner's answer: under the sound model the plan (its committed part and escape), a
safe step in lane, what the last decision proved, or the fallback; under the paper's rules the plan, the plan under
way, or a wait in lane. The rules, apart from their execution: the drivers (``sim.driver.sound``,
``sim.driver.paper``) ask the questions they need (lazily: some of them watch the world) and run what they choose."""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass

from sim.driver.control import K_X
from spec.actions import Action
from spec.answers import Status
from spec.envelope import SPEED_LAG_MPS, Tracking
from spec.lanes import Lane

#: The final model's answers that refuse an overtake (no failure of the planner).
NO_OVERTAKE = (Status.NO_PLAN, Status.NO_PLAN_WITHIN_HORIZON)


class Act(enum.Enum):
    """What a decision does."""

    PLAN = "plan"  # the answer's plan: its committed part, then its escape (a whole plan: to its end)
    STEP = "step in lane"  # one safe step in lane (``oracle.sound.keep_lane``)
    KEEP = "keep the last proof"  # the rest of the last decision's plan and escape, or its minimal-risk manoeuvre
    FALLBACK = "fallback"  # ``spec.envelope.MinimalRisk``


@dataclass(frozen=True, slots=True)
class Choice:
    """A decision's act, why (the answer's status, or why its plan was not taken) and, for a step, which."""

    act: Act
    why: str
    step: Action | None = None


def planner_failed(status: Status) -> bool:
    """Whether the answer is a failure of the planner: neither a plan, nor a refusal of the overtake, nor a start
    that already breaks the safety specification (an assumption broke before the snapshot: counted apart)."""
    return status not in (Status.PLAN, Status.UNSAFE_START, *NO_OVERTAKE)


def choose(status: Status, planned: bool, *, refused: Callable[[], bool], step: Callable[[], Action | None],
           unsafe_before: bool, pending: bool, proved_holds: Callable[[], bool]) -> Choice:
    """A decision's act from its answer's ``status`` (``planned``: a plan with actions):

    - a plan, unless the tracker's contradiction ``refused`` the overtake it starts;
    - else a safe ``step`` in lane, if there is one;
    - else what the last decision proved, while its assumptions hold (``proved_holds``), unless this start breaks
      the safety specification again right after the last decision's start did (``unsafe_before``) with nothing of
      its plan left (not ``pending``): its minimal-risk manoeuvre would keep the broken gap, the fallback opens it;
    - else the fallback.

    Each question is asked only when the rules reach it, in this order (``refused``, ``proved_holds`` act on what the
    AV senses)."""
    why = status.value
    if status is Status.PLAN and planned:
        if not refused():
            return Choice(Act.PLAN, why)
        why = "an overtake refused: the tracker holds a contradiction"
    safe = step()
    if safe is not None:
        return Choice(Act.STEP, why, safe)
    unsafe_again = status is Status.UNSAFE_START and unsafe_before and not pending
    if not unsafe_again and proved_holds():
        return Choice(Act.KEEP, why)
    return Choice(Act.FALLBACK, f"{why}, and no safe step in lane")


def plan_start(car_x_m: float, car_mps: float, ref_x_m: float, ref_mps: float,
               tracking: Tracking) -> tuple[float, float] | None:
    """Where and how fast a sound decision's plan starts: on the proved reference the car runs on (its place and
    speed), so that the next proof covers the car wherever the envelope (``tracking``) lets it be about that reference,
    as the last proof did, and the reference runs on unbroken: replanning from the planned state, as Pek and Althoff's
    online verification does. A start at the car instead restarts the reference there, and puts the envelope about
    where the car is and its measured speed, where the last proof put it about the reference: a plan that left the
    reference at its least gap then finds the next start unsafe.

    Only while the controller's pull back towards the reference (``K_X`` per metre off it) and the car's speed error
    leave, within the envelope's speed error, the car's measured lag behind a reference that changes speed
    (``SPEED_LAG_MPS``): a car that a slow lane change left a metre behind would otherwise chase the reference while it
    brakes, past the envelope. None: at the car, its reference restarted there."""
    if K_X * abs(car_x_m - ref_x_m) + abs(car_mps - ref_mps) > tracking.speed_mps - SPEED_LAG_MPS:
        return None
    return ref_x_m, ref_mps


class PaperAct(enum.Enum):
    """What a decision under the paper's rules does."""

    EXECUTE = "execute the plan"
    KEEP = "keep the plan under way"  # for at most ``LOOP.replan_after_actions`` actions (``PaperDriver.keep``)
    WAIT = "wait in lane without a plan"
    DRIVE = "drive on: nothing to overtake"
    HOLD = "drive on in lane: an overtake refused"


def paper_choice(status: Status, planned: bool, pending: bool, *, refused: Callable[[], bool]) -> PaperAct:
    """A paper-model decision's act from its answer's ``status`` (``planned``: a plan with actions): without a plan,
    the rest of the plan under way (``pending``: a re-plan mid-manoeuvre that finds none does not undo the plan
    being executed, as the paper warns), else a wait; a plan without actions (nothing to overtake) drives on; a plan
    the tracker's contradiction ``refused`` (asked only then) drives on in lane; any other plan is executed."""
    if status is not Status.PLAN:
        return PaperAct.KEEP if pending else PaperAct.WAIT
    if not planned:
        return PaperAct.DRIVE
    return PaperAct.HOLD if refused() else PaperAct.EXECUTE


def only_followers_behind(lane: Lane, lane_due: Lane | None) -> bool:
    """Whether a left-lane vehicle behind the AV's centre can only be one that follows it (``Monitor.sense``):
    the action under way started in the left ``lane`` and has not put the AV wholly into the right one (``lane_due``:
    the lane it must be wholly in now, None during a sideways move; an action in lane, or the move out); from the
    right lane a vehicle it passed, or is returning behind, can be there."""
    return lane is Lane.LEFT and lane_due is not Lane.RIGHT
