"""The sound model's decision rules (``sim.driver.decide``), each at its boundary, with scripted answers to the
questions the simulator would ask: no planner, no physics engine."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from sim.driver.control import K_X
from sim.driver.decide import (
    Act,
    Choice,
    PaperAct,
    choose,
    only_followers_behind,
    paper_choice,
    plan_start,
    planner_failed,
)
from spec.actions import Action
from spec.answers import Status
from spec.envelope import EXACT_AV, SPEED_LAG_MPS, TRACKING
from spec.lanes import Lane


def asked(log: list[str], name: str, value: object) -> Callable[[], object]:
    def answer() -> object:
        log.append(name)
        return value
    return answer


def decide(status: Status, planned: bool = True, *, refused: bool = False, step: Action | None = None,
           unsafe_before: bool = False, pending: bool = False, holds: bool = True) -> tuple[Choice, list[str]]:
    log: list[str] = []
    choice = choose(status, planned, refused=asked(log, "refused", refused),  # type: ignore[arg-type]
                    step=asked(log, "step", step), unsafe_before=unsafe_before, pending=pending,  # type: ignore[arg-type]
                    proved_holds=asked(log, "holds", holds))  # type: ignore[arg-type]
    return choice, log


def test_a_plan_is_executed_unless_the_tracker_refuses_the_overtake_it_starts() -> None:
    assert decide(Status.PLAN) == (Choice(Act.PLAN, "plan"), ["refused"])
    choice, log = decide(Status.PLAN, refused=True, step=Action.DRIVE)
    assert choice == Choice(Act.STEP, "an overtake refused: the tracker holds a contradiction", Action.DRIVE)
    assert log == ["refused", "step"]


def test_an_empty_plan_is_no_plan_to_execute_it_keeps_the_lane() -> None:
    choice, log = decide(Status.PLAN, planned=False, step=Action.DRIVE)
    assert choice.act is Act.STEP and log == ["step"]


@pytest.mark.parametrize("status", [Status.NO_PLAN, Status.NO_PLAN_WITHIN_HORIZON, Status.UNSAFE_START,
                                    Status.INCOMPLETE])
def test_without_a_plan_a_safe_step_in_lane_then_the_last_proof_then_the_fallback(status: Status) -> None:
    assert decide(status, step=Action.DRIVE)[0] == Choice(Act.STEP, status.value, Action.DRIVE)
    assert decide(status) == (Choice(Act.KEEP, status.value), ["step", "holds"])
    choice, _ = decide(status, holds=False)
    assert choice == Choice(Act.FALLBACK, f"{status.value}, and no safe step in lane")


def test_a_start_that_breaks_the_specification_twice_in_a_row_with_nothing_left_to_keep_goes_to_the_fallback() -> None:
    """Seed 9 of the paper's world: the last decision's minimal-risk manoeuvre held the vehicle ahead's speed and
    kept a broken gap for the rest of the drive. The second such start in a row, nothing of the last plan pending,
    hands over to the fallback without asking the last proof; the first one, or one with a plan pending, keeps it."""
    choice, log = decide(Status.UNSAFE_START, unsafe_before=True)
    assert choice.act is Act.FALLBACK and log == ["step"]
    assert decide(Status.UNSAFE_START, unsafe_before=False)[0].act is Act.KEEP
    assert decide(Status.UNSAFE_START, unsafe_before=True, pending=True)[0].act is Act.KEEP
    assert decide(Status.NO_PLAN, unsafe_before=True)[0].act is Act.KEEP  # only a start that breaks it again
    assert decide(Status.UNSAFE_START, unsafe_before=True, step=Action.DRIVE)[0].act is Act.STEP


def test_only_an_answer_that_is_neither_a_plan_a_refusal_nor_an_unsafe_start_is_the_planners_failure() -> None:
    assert [s for s in Status if planner_failed(s)] == [
        s for s in Status if s not in (Status.PLAN, Status.NO_PLAN, Status.NO_PLAN_WITHIN_HORIZON, Status.UNSAFE_START)]
    assert planner_failed(Status.INCOMPLETE) and not planner_failed(Status.UNSAFE_START)


@pytest.mark.parametrize(("status", "planned", "pending", "refused", "act", "was_asked"), [
    (Status.PLAN, True, False, False, PaperAct.EXECUTE, True),
    (Status.PLAN, True, True, True, PaperAct.HOLD, True),
    (Status.PLAN, False, True, True, PaperAct.DRIVE, False),  # nothing to overtake: drives on, never refused
    (Status.NO_PLAN, False, True, True, PaperAct.KEEP, False),  # a re-plan mid-manoeuvre keeps the plan under way
    (Status.INCOMPLETE, False, True, False, PaperAct.KEEP, False),
    (Status.NO_PLAN_WITHIN_HORIZON, False, False, False, PaperAct.WAIT, False),
    (Status.INCOMPLETE, False, False, False, PaperAct.WAIT, False),
])
def test_a_paper_decision_executes_keeps_waits_or_drives_on_as_its_answer_says(
        status: Status, planned: bool, pending: bool, refused: bool, act: PaperAct, was_asked: bool) -> None:
    log: list[str] = []
    got = paper_choice(status, planned, pending, refused=asked(log, "refused", refused))  # type: ignore[arg-type]
    assert got is act and (log == ["refused"]) is was_asked


@pytest.mark.parametrize(("lane", "due", "only"), [
    (Lane.LEFT, Lane.LEFT, True),  # an action in lane
    (Lane.LEFT, None, True),  # the move out, under way
    (Lane.LEFT, Lane.RIGHT, False),  # the move out, done: the AV wholly in the right lane
    (Lane.RIGHT, Lane.RIGHT, False),  # passing in the right lane
    (Lane.RIGHT, None, False),  # the return, under way
    (Lane.RIGHT, Lane.LEFT, False),  # the return, done: the vehicle passed may be behind
])
def test_a_vehicle_behind_is_only_a_follower_while_the_action_started_in_the_left_lane_keeps_the_av_out_of_the_right(
        lane: Lane, due: Lane | None, only: bool) -> None:
    assert only_followers_behind(lane, due) is only


#: What the envelope's speed error leaves above the car's lag: the most the pull back and the speed error may take.
ROOM_MPS = TRACKING.speed_mps - SPEED_LAG_MPS


@pytest.mark.parametrize(("off_m", "off_mps", "on_reference"), [
    (0.0, 0.0, True),
    (ROOM_MPS / K_X, 0.0, True),  # at the edge: the whole room taken by the pull back
    (-ROOM_MPS / K_X, 0.0, True),
    (0.0, -ROOM_MPS, True),
    (ROOM_MPS / K_X / 2, ROOM_MPS / 2, True),
    (ROOM_MPS / K_X + 1e-6, 0.0, False),
    (0.0, ROOM_MPS + 1e-6, False),
    (ROOM_MPS / K_X / 2, -ROOM_MPS / 2 - 1e-6, False),
    (TRACKING.position_m, 0.0, False),  # within the envelope, but the pull back would take the car out of it
])
def test_a_plan_starts_on_the_reference_while_the_pull_back_towards_it_fits_the_envelope(
        off_m: float, off_mps: float, on_reference: bool) -> None:
    start = plan_start(100.0 + off_m, 7.0 + off_mps, 100.0, 7.0, TRACKING)
    assert start == ((100.0, 7.0) if on_reference else None)


def test_an_av_without_an_envelope_always_plans_from_the_car() -> None:
    assert plan_start(100.0, 7.0, 100.0, 7.0, EXACT_AV) is None
