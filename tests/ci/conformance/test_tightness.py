"""Tightness of the sound model (``ci.conformance.tightness``): every refusal is classified, the unjustified ones are
the documented findings, and the witness check is not vacuous."""

from __future__ import annotations

from collections import deque
from dataclasses import replace

from ci.conformance import tightness
from ci.conformance.tightness import Refusal, Tightness, Where
from oracle.sound import _paper, rules_for, start
from spec.actions import Action
from spec.assumptions import profile
from spec.commitment import lane_after
from spec.escapes import COMMIT, ESCAPES
from spec.grid import grid_for
from spec.lanes import Lane
from spec.models import ModelKind, models_for
from spec.rules import disabled_guard
from spec.safety import Conflict
from spec.scenario import Scenario, make_scenario, problem_for
from spec.sound import Sound


def _with(name: str, lane: str, left: list[int], right: list[int], targets: int) -> Scenario:
    return replace(make_scenario(lane, left, right, targets), sound=Sound(profile(name)))


#: Two scenarios of the conformance example sweep's seeded sample (``ci.conformance.tightness``, seed 2026), on the
#: paper grid.
OVERTAKE = _with("default", "left", [12, 15], [14], 2)  # every refusal exhibited by a motion
RETURN = _with("paper", "right", [9, 17], [18], 0)  # both findings of an earlier model (docs/sound.md)
#: The same where followers react (the paper's keep their speed, and a braking AV then has them in conflict: BEHIND).
RETURN_REACTING = replace(RETURN, sound=Sound(replace(profile("paper"), followers_react=True)))


def _refusals(scenario: Scenario) -> list[tuple[ModelKind, Refusal]]:
    out = []
    for kind in models_for(scenario.model):
        found, _, capped = tightness.refusals(problem_for(scenario, kind))
        assert not capped
        out += [(kind, r) for r in found]
    return out


def test_every_refusal_is_classified_and_only_the_documented_findings_are_unjustified() -> None:
    for scenario, neither in ((OVERTAKE, {}), (RETURN, {})):
        counts = tightness.measure(scenario)
        classified = sum(n for tally in counts.by_where.values() for n in tally.values())
        assert classified == len(_refusals(scenario))
        found = {(f, w): n for f, tally in counts.findings.items() for w, n in tally.items() if n}
        assert found == neither  # a model fix that removes a finding must update these counts and the docs
        assert sum(counts.by_where[w][Tightness.NEITHER] for w in Where) == sum(neither.values())
        assert counts.thin == 0


def test_a_refusal_with_its_vehicle_moved_far_away_is_exhibited_by_no_motion() -> None:
    exhibited = []
    for kind, r in _refusals(OVERTAKE):
        verdict = tightness.classify(problem_for(OVERTAKE, kind), r)
        if verdict.tightness is Tightness.EXHIBITED:
            exhibited.append(r)
    conflicts = {r.violation.conflict for r in exhibited}
    assert {Conflict.AHEAD, Conflict.ONCOMING} <= conflicts
    for r in exhibited[:: max(1, len(exhibited) // 40)]:
        v = r.violation
        # in its favour: out of reach for the whole horizon
        away = -1e4 if v.conflict in (Conflict.CUT_IN, Conflict.BEHIND) else 1e4
        moved = replace(v, vehicle=replace(v.vehicle, lo_m=v.vehicle.lo_m + away, hi_m=v.vehicle.hi_m + away))
        far = replace(r, violation=moved)
        assert tightness.witness(OVERTAKE, r) is not None
        assert tightness.corner_witness(OVERTAKE, far) is None
        assert tightness.witness(OVERTAKE, far) is None, r.describe()


def test_a_witness_breaks_the_specification_by_what_it_says() -> None:
    _, r = next((k, r) for k, r in _refusals(OVERTAKE) if r.violation.conflict is Conflict.AHEAD)
    shown = tightness.witness(OVERTAKE, r)
    assert shown is not None and shown.gap_m < shown.required_m
    sound = OVERTAKE.sound
    assert sound is not None
    low, high = sound.bounds.same_mps.low_mps, sound.bounds.same_mps.high_mps
    assert r.violation.vehicle.lo_m <= shown.start_m <= r.violation.vehicle.hi_m and low <= shown.speed_mps <= high
    assert abs(shown.av_offset_m) <= sound.tracking.position_m and abs(shown.av_speed_offset_mps) <= \
        sound.tracking.speed_mps


def test_a_plan_ending_at_the_hold_speed_is_not_refused() -> None:
    """After the minimal-risk manoeuvre the AV's reference is at most as fast as the slowest vehicle ahead (the hold
    speed is the slowest speed, to float rounding): nothing closes in, so the end is not refused, even
    where the ramp's end speed comes out a rounding above the hold speed (the finding ``NOTHING_CLOSES_IN`` of an
    earlier model: 2,392 refusals of this scenario)."""
    sound = RETURN.sound
    assert sound is not None
    low = sound.bounds.same_mps.low_mps
    above = 0
    for kind in models_for(RETURN.model):
        problem = problem_for(RETURN, kind)
        rules, first = rules_for(problem), start(problem)
        seen, queue = {first.key()}, deque([first])
        while queue:
            state = queue.popleft()
            ((_, pieces),) = rules.window(state, None)
            tail = pieces[-1].piece
            end_x, end_v = tail.x(tail.t1_s), tail.v(tail.t1_s)
            if state.lane is Lane.LEFT and end_v > low and abs(end_v - low) < 1e-9 and any(
                    rules.held_ahead(v, end_x, tail.t1_s) for v in rules.same):
                above += 1
                assert rules.continuation_violation(state) is None, state
            if state.steps >= 4:
                continue
            for action in Action:
                if disabled_guard(_paper(state), action, problem.rules) is None and \
                        rules.step_violation(state, action) is None:
                    nxt = rules.after(state, action)
                    if nxt.key() not in seen:
                        seen.add(nxt.key())
                        queue.append(nxt)
    assert above > 0  # the sample has such ends: the test is not vacuous


def test_a_follower_is_never_held_ahead() -> None:
    """A vehicle behind the AV when it gets into the left lane follows it, even once its interval would be clear
    ahead of an AV that braked (the finding ``FOLLOWER_AHEAD`` of an earlier model, 76 refusals of this scenario):
    after left_lane_change, brake, brake, drive, accelerate is safe (left_lane[0] started 21 m behind) where followers
    react; where they keep their speed, the first brake is refused for that follower (BEHIND)."""
    keeping = problem_for(RETURN, ModelKind.FINAL)
    after_return = rules_for(keeping).after(start(keeping), Action.LEFT_LANE_CHANGE)
    found = rules_for(keeping).step_violation(after_return, Action.BRAKE)
    assert found is not None and found.conflict is Conflict.BEHIND and found.vehicle.name.startswith("left_lane[0]")
    for kind in models_for(RETURN_REACTING.model):
        problem = problem_for(RETURN_REACTING, kind)
        rules, state = rules_for(problem), start(problem)
        for action in (Action.LEFT_LANE_CHANGE, Action.BRAKE, Action.BRAKE, Action.DRIVE):
            assert rules.step_violation(state, action) is None
            state = rules.after(state, action)
        follower = next(i for i, v in enumerate(rules.same) if v.name.startswith("left_lane[0]"))
        assert state.followers is not None and follower in state.followers
        t_s = state.t_units * rules.unit_s
        assert rules.held_ahead(rules.same[follower], rules.reference(state, None).position_m(t_s), t_s)
        assert rules.step_violation(state, Action.ACCELERATE) is None


def test_a_plan_may_end_with_a_follower_clear_ahead_of_a_braking_av() -> None:
    """The minimal-risk manoeuvre's window skips followers too (the tightness run's end refusals, all of them this):
    lane=right left=[18, 34] right=[36] at 10.5 m, default profile, after accelerate, left_lane_change, drive, drive,
    twelve brakes and accelerate, left_lane[0] (behind when the AV got into the left lane) is no conflict."""
    scenario = replace(make_scenario("right", [18, 34], [36], 0, cell_m="10.5"), sound=Sound(profile("default")))
    problem = problem_for(scenario, ModelKind.FINAL)
    rules, state = rules_for(problem), start(problem)
    for action in [Action.ACCELERATE, Action.LEFT_LANE_CHANGE, Action.DRIVE, Action.DRIVE] + [Action.BRAKE] * 12 + \
            [Action.ACCELERATE]:
        assert rules.step_violation(state, action) is None
        state = rules.after(state, action)
    assert state.followers is not None and 0 in state.followers and rules.same[0].name.startswith("left_lane[0]")
    assert rules.continuation_violation(state) is None


# -- the commitment semantics --------------------------------------------------------------------------------------
def _committing(scenario: Scenario) -> Scenario:
    assert scenario.sound is not None
    return replace(scenario, sound=replace(scenario.sound, commitment=COMMIT))


def test_every_refused_first_step_is_exhibited_under_every_escape() -> None:
    """Under the commitment semantics each enabled first action is committed or refused, and a refused one is
    justified under each escape allowed after it (both sample scenarios: every one exhibited by a motion)."""
    for scenario in (OVERTAKE, RETURN, RETURN_REACTING):
        counts = tightness.measure_commit(_committing(scenario))
        steps = counts.by_where[Where.STEP]
        assert counts.enabled == counts.committable + sum(steps.values()) and counts.no_escape == 0
        assert sum(steps.values()) > 0 and counts.committable > 0  # refuses some, commits to some: not vacuous
        assert steps[Tightness.EXHIBITED] == sum(steps.values()), scenario
        assert counts.escapes[Tightness.EXHIBITED] == sum(counts.escapes.values()) >= sum(steps.values())
        assert counts.thin == 0


def test_an_escape_refusal_with_its_vehicle_moved_far_away_is_exhibited_by_no_motion() -> None:
    """The witness under an escape is found on the AV's reference through the action and the escape, and only for
    a vehicle that can reach it."""
    scenario = _committing(OVERTAKE)
    problem = problem_for(scenario, ModelKind.FINAL)
    rules, first = rules_for(problem), start(problem)
    tried = 0
    for action in Action:
        if disabled_guard(_paper(first), action, problem.rules) is not None:
            continue
        for escape in COMMIT.allowed(lane_after(first.lane, (action,))):
            r = tightness.escape_refusal(rules, first, action, escape)
            if r is None:
                continue
            verdict = tightness.classify_escape(problem, first, action, escape, r)
            assert verdict.tightness is Tightness.EXHIBITED and verdict.witness is not None
            v = r.violation
            away = -1e4 if v.conflict in (Conflict.CUT_IN, Conflict.BEHIND) else 1e4
            far = replace(r, violation=replace(v, vehicle=replace(v.vehicle, lo_m=v.vehicle.lo_m + away,
                                                                   hi_m=v.vehicle.hi_m + away)))
            path = tightness.Path((action, *escape.actions), scenario.sound, scenario.grid, scenario.lane)
            assert tightness.witness(scenario, far, path=path) is None, r.describe()
            tried += 1
    assert tried >= 3


def test_the_step_checked_whole_refused_is_committed_under_the_commitment_semantics() -> None:
    """The over-conservative refusal of the whole-plan model (#58: at 5.25 m, ``accelerate`` refused as if held to
    its end) is a refusal the whole-plan walk meets and the commitment semantics does not: the step commits, with an
    escape proved after it."""
    base = replace(make_scenario("left", [48, 76], [], 2, grid=grid_for(5.25)), sound=Sound(profile("default")))
    problem = problem_for(base, ModelKind.FINAL)
    rules, first = rules_for(problem), start(problem)
    assert rules.step_violation(first, Action.ACCELERATE) is not None
    escapes = [e for e in ESCAPES if e.from_lane is Lane.LEFT]
    assert any(tightness.escape_refusal(rules, first, Action.ACCELERATE, e) is None for e in escapes)
    counts = tightness.measure_commit(_committing(base))
    assert counts.committable >= 1 and counts.by_where[Where.STEP][Tightness.NEITHER] == 0


def test_an_unsafe_start_of_a_vehicle_that_may_be_just_ahead_is_exhibited() -> None:
    """The vehicle in the cell ahead of the AV's may be behind it (it follows) or clear ahead far too near: the witness
    is the motion just past ``spec.sound.follower_limit_m``, not an end of its interval (each end is safe: behind, it
    follows; at its far end it is clear ahead with its gap)."""
    counts = tightness.measure_commit(_with("default", "left", [11], [], 1))
    assert counts.by_where[Where.START] == {Tightness.EXHIBITED: 2, Tightness.ROUNDING: 0, Tightness.NEITHER: 0}


def test_an_unsafe_start_of_a_vehicle_that_can_only_be_behind_is_exhibited_as_behind() -> None:
    """Where followers keep their speed (``paper``), the vehicle in the cell behind the AV's reaches its centre: it
    cannot be clear ahead of the AV, nor is it bumpers clear behind the AV's rearmost position. The start is refused
    as ``behind``, and the witness is a motion behind the AV that the AV's envelope reaches, not one taken as ahead."""
    scenario = _with("paper", "left", [9], [], 0)
    for kind in models_for(scenario.model):
        problem = problem_for(scenario, kind)
        first = start(problem)
        hit = tightness.sound_rules(problem).start_violation(first)
        assert hit is not None and hit.conflict is Conflict.BEHIND
        shown = tightness.witness(scenario, Refusal(Where.START, first, (), None, hit))
        assert shown is not None and shown.conflict is Conflict.BEHIND and shown.gap_m < shown.required_m
        assert shown.start_m < 0.0
