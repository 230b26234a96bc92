"""The fallback's rules (``sim.driver.fallback``, ``spec.envelope.MinimalRisk``), each at its boundary, from
constructed neighbours and speeds: no physics engine."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from sim.driver import fallback
from sim.driver.nearest import Nearest
from sim.driver.readings import Reading
from spec.assumptions import PROFILES, SpeedBounds
from spec.envelope import MINIMAL_RISK, TRACKING
from spec.lanes import Lane
from spec.motion import SpeedProfile
from spec.physical import CAR, SENSORS
from spec.safety import SAFETY


def around(lead: Nearest | None = None, follower: Nearest | None = None, oncoming: Nearest | None = None, *,
           swept: bool = True, react: bool = True, slowest_mps: float = 4.9,
           oncoming_high_mps: float = 9.0) -> fallback.Around:
    """What the fallback knows: these neighbours, under the paper's bounds with the given followers and speeds."""
    paper = PROFILES["paper"]
    bounds = replace(paper, followers_react=react, same_mps=SpeedBounds(slowest_mps, paper.same_mps.high_mps),
                     oncoming_mps=SpeedBounds(paper.oncoming_mps.low_mps, oncoming_high_mps))
    return fallback.Around(lead, follower, oncoming, swept, bounds)


@pytest.mark.parametrize(("gap_m", "closing_mps", "react", "blocks"),
                         [(30.0, 1.0, False, False), (3.0, 1.0, False, True), (3.0, 1.0, True, False),
                          (30.0, None, False, True), (30.0, 2.0, False, True), (30.0, 12.0, False, True)])
def test_a_follower_that_keeps_its_speed_blocks_the_return_while_nearer_than_the_specification_allows(
        gap_m: float, closing_mps: float | None, react: bool, blocks: bool) -> None:
    """Seeds 6 and 8 of the faults evaluation (paper traffic, whose followers never brake): the fallback returned
    from the right lane slower than the vehicle behind and was rear-ended; seed 21 of the reliability campaign: 31 m
    ahead of one closing at 6.8 m/s (the gap enough for the lane change's 3 s) it returned from a standstill, and the
    sideways move took 5 s. A follower closing faster than the fit's error (``MinimalRisk.open_mps``) blocks."""

    follower = Nearest(gap_m + CAR.length_m, closing_mps)
    assert fallback.follower_blocks(around(follower=follower, react=react), 8.0, 2.0) is blocks


def test_the_fallback_passing_a_vehicle_beside_it_is_held_back_only_by_a_gap_ahead_that_breaks_the_spec_now(
        ) -> None:
    """Seed 22 of the reliability campaign: in the right lane, 3.6 m ahead of a vehicle it was passing, the fallback
    matched the speed of a "vehicle ahead" (a fake gap's copy) 20 m on, because a return would have left too small a
    gap to it, and stayed beside the vehicle until the oncoming one left no time. Passing, the AV stays at least
    ``open_mps`` faster than the vehicle beside it while the gap ahead meets the specification now."""

    beside = Nearest(3.6, -1.0, behind=True)  # 3.6 m behind the AV's centre, the AV 1 m/s the faster

    def target(lead: Nearest, follower: Nearest = beside) -> float | None:
        return fallback.waiting_mps(around(lead, follower), 8.0, True, True, False)

    closing = 2.0  # on the vehicle ahead, at 6 m/s
    far = Nearest(SAFETY.required_gap_m(closing) + CAR.length_m + 5.0, closing)
    assert target(far) == pytest.approx(7.0 + MINIMAL_RISK.open_mps)  # on past it
    assert target(far, Nearest(3.6, 2.0, behind=True)) == pytest.approx(6.0)  # the one beside the faster: no pass
    near = Nearest(SAFETY.required_gap_m(closing) + CAR.length_m - 0.5, closing)
    assert target(near) == pytest.approx(6.0)  # the gap ahead too small now: its speed


def test_the_fallback_drops_back_behind_a_vehicle_beside_it_at_that_vehicles_speed_not_to_a_standstill() -> None:
    """Seed 38 of the reliability campaign (48254f9): a reading beside the AV in the left lane, 0.9 m ahead of its
    centre and moving away at 2.7 m/s, became the vehicle ahead; the fallback's target was ``open_mps`` below the
    AV's own speed, every control step, so it braked from 4.4 m/s to a standstill in the right lane while an oncoming
    vehicle closed, and the forced return later cut in front of a follower. Beside a vehicle it is not faster than,
    it now drives ``open_mps`` below that vehicle's speed."""

    target = fallback.waiting_mps(around(Nearest(0.9, -2.7)), 4.0, True, False, False)
    assert target == pytest.approx(4.0 + 2.7 - MINIMAL_RISK.open_mps)
    level = around(Nearest(0.9, 0.0))  # at the AV's speed: below it
    assert fallback.waiting_mps(level, 4.0, True, False, False) == pytest.approx(4.0 - MINIMAL_RISK.open_mps)


def test_the_fallback_beside_a_vehicle_it_is_faster_than_drops_back_or_passes_whichever_ends_sooner() -> None:
    """Seed 51 of the 1,000 km campaign (8a81810): waiting in the right lane at 8.19 m/s behind a left-lane vehicle
    at 7.0 m/s whose gap had fallen to 1.25 m (below the least gap), the fallback had no rule for a vehicle ahead it
    is the faster of, kept its speed and crept alongside at 1.2 m/s (a 10 s pass) until the oncoming vehicle (73 m,
    closing at 15.2 m/s) forced a return into it. It now drops back, ``open_mps`` below that vehicle's speed, when
    that ends sooner than the pass (about 1 s here); 5 m/s the faster and nearly level, it passes on (1.4 s against
    6 s); beside a vehicle standing it cannot drop back and passes; with the vehicle's speed not measured, it keeps
    its own."""
    mr = MINIMAL_RISK

    def target(lead: Nearest, speed_mps: float = 8.19, follower: Nearest | None = None) -> float | None:
        return fallback.waiting_mps(around(lead, follower), speed_mps, True,
                                    follower is not None and follower.gap_m < 2.0, False)

    assert target(Nearest(1.25 + CAR.length_m, 8.19 - 7.0)) == pytest.approx(7.0 - mr.open_mps)
    assert target(Nearest(-0.5 + CAR.length_m, 8.19 - 7.0)) == pytest.approx(7.0 - mr.open_mps)
    assert target(Nearest(1.25 + CAR.length_m, None)) is None  # not measured: the speed it has
    assert target(Nearest(0.5, 5.0), speed_mps=12.0) == 12.0  # passing ends sooner: the speed it has, 5 m/s faster
    assert target(Nearest(5.0, 1.0), speed_mps=1.0) == mr.open_mps  # beside a vehicle standing: it passes
    assert mr.pass_s(1.19, 1.25 + CAR.length_m) == pytest.approx(8.2, abs=0.1)  # up to 1.5 m/s the faster
    assert mr.drop_back_s(1.19, 1.25 + CAR.length_m, 7.0) == pytest.approx(0.9, abs=0.1)
    assert mr.pass_s(5.0, 0.5) == pytest.approx(1.4) and mr.drop_back_s(5.0, 0.5, 7.0) == pytest.approx(6.35, abs=0.05)
    assert mr.pass_s(0.0, 0.5) == pytest.approx(4.94, abs=0.01) and mr.drop_back_s(1.0, 5.0, 0.0) == math.inf
    # a vehicle alongside behind, 2.5 m behind the AV's centre and 4 m behind the one ahead's: no slot between them;
    # a drop back ends behind it too (6.7 s), longer than passing the one ahead (5.25 s)
    behind = Nearest(2.5, -2.0, behind=True)  # at 7 m/s
    assert target(Nearest(4.0, 2.0), speed_mps=9.0, follower=behind) == pytest.approx(9.0)  # on past both
    # a vehicle 9.5 m behind the AV, 13.5 m behind the one ahead: room for the AV between them, it drops back into it
    assert target(Nearest(4.0, 0.5), speed_mps=7.5, follower=Nearest(9.5, -0.5, behind=True)) == pytest.approx(
        7.0 - mr.open_mps)


def test_the_fallback_beside_a_vehicle_alongside_behind_passes_it_when_that_ends_sooner_and_leaves_it_room() -> None:
    """Seed 69 of the 1,000 km campaign (94bbc05): waiting in the right lane at 6.96 m/s beside a left-lane vehicle
    whose centre was 6.0 m behind the AV's (0.5 m short of clear) and 0.04 m/s the faster, with the vehicle ahead
    15 m on, the fallback dropped back behind it (``open_mps`` below its speed), 12.5 m at the speeds it ran; 6 s
    later the oncoming lane forced the return while that vehicle was still beside it, and the two touched. Passing
    it, speeding up to ``open_mps`` the faster, ends in 0.6 s against 8.5 s, and the slot ahead of it takes the AV:
    it passes. With no slot (the vehicle ahead 6.9 m on, or 11 m on and not measured: it may stand), or level with
    the vehicle, it drops back; the faster of the two, it passes whatever comes."""
    mr = MINIMAL_RISK

    ahead = Nearest(14.99, -0.04)  # at 7.0 m/s

    def target(follower: Nearest, lead: Nearest | None = ahead) -> float | None:
        return fallback.waiting_mps(around(lead, follower), 6.96, False, True, True)

    beside = Nearest(6.01, 0.04, behind=True)  # at 7.0 m/s
    assert mr.pass_s(-0.04, -6.01) == pytest.approx(0.62, abs=0.01)
    assert mr.drop_back_s(-0.04, -6.01, 7.0) == pytest.approx(8.46, abs=0.01)
    assert target(beside) == pytest.approx(7.0 + mr.open_mps)  # on past it
    assert target(beside, lead=None) == pytest.approx(7.0 + mr.open_mps)  # nothing ahead: room
    assert target(beside, lead=Nearest(6.9, -0.04)) == pytest.approx(7.0 - mr.open_mps)  # no slot: drops back
    assert target(beside, lead=Nearest(11.0, -0.04)) == pytest.approx(7.0 + mr.open_mps)  # 11 m on at 7 m/s: room
    assert target(beside, lead=Nearest(11.0, None)) == pytest.approx(7.0 - mr.open_mps)  # it may stand: none
    level = Nearest(0.0, 0.04, behind=True)  # level with the AV: passing takes 4.63 s, dropping back 4.45 s
    assert target(level) == pytest.approx(7.0 - mr.open_mps)
    assert target(Nearest(0.3, 0.04, behind=True)) == pytest.approx(7.0 + mr.open_mps)  # 4.43 s against 4.65 s
    # the AV the faster, it passes at least ``open_mps`` the faster
    assert target(Nearest(6.01, -1.0, behind=True)) == pytest.approx(5.96 + mr.open_mps)
    assert target(Nearest(6.01, -2.0, behind=True), lead=Nearest(6.9, -0.04)) == pytest.approx(6.96)


def test_a_return_that_would_end_too_near_the_vehicle_ahead_brakes_to_its_speed_from_its_start() -> None:
    """Seed 23 (the code of 4952935): the oncoming lane forced the return while the vehicle ahead in the left lane was
    5.1 m away closing at 3 m/s; the return ran at constant speed into it. A return that would end nearer the vehicle
    ahead than the specification allows brakes from its start, at the car's limit, to that vehicle's speed (not
    fitted yet: the slowest the bounds let it be)."""
    change_s = fallback.RETURN_S
    slowest_mps = 4.9

    def profile(lead: Nearest | None, speed_mps: float = 10.0) -> SpeedProfile:
        return fallback.return_profile(around(lead, slowest_mps=slowest_mps), speed_mps)

    assert profile(None).at(change_s) == pytest.approx(10.0)  # nothing ahead: the speed it starts at
    closing = 3.0
    # room at its end, the car's envelope taken (``MinimalRisk.too_near_after``): as before
    envelope_m = TRACKING.position_m
    room = Nearest(SAFETY.required_gap_m(closing + TRACKING.speed_mps) + closing * change_s + envelope_m
                   + CAR.length_m + 0.5, closing)
    assert profile(room).at(change_s) == pytest.approx(10.0)
    # room only for a car exactly on its reference: brakes
    assert profile(Nearest(SAFETY.required_gap_m(closing) + closing * change_s + CAR.length_m + 0.5,
                           closing)).at(change_s) == pytest.approx(7.0)
    near = Nearest(5.1 + CAR.length_m, closing)
    braking = profile(near)
    assert braking.at(0.0) == pytest.approx(10.0)
    assert braking.at(change_s) == pytest.approx(7.0)  # the vehicle ahead's speed
    assert braking.at(closing / MINIMAL_RISK.emergency_decel_mps2) == pytest.approx(7.0)  # at the car's limit
    # its speed not fitted yet: the slowest the bounds let it be, not a standstill (seeds 13 and 16 at 6994c0a: the AV
    # stood across the lanes and the vehicle it had passed ran into it)
    assert profile(Nearest(5.1 + CAR.length_m, None)).at(change_s) == pytest.approx(slowest_mps)
    unfitted_room = SAFETY.required_gap_m(10.0 - slowest_mps + TRACKING.speed_mps) + (10.0 - slowest_mps) * change_s \
        + envelope_m + CAR.length_m + 0.5
    assert profile(Nearest(unfitted_room, None)).at(change_s) == pytest.approx(10.0)
    assert profile(Nearest(5.1 + CAR.length_m, -1.0)).at(change_s) == pytest.approx(10.0)  # moving away: no brake


def test_a_forced_return_passing_a_vehicle_alongside_brakes_for_the_one_ahead_only_once_clear_of_it() -> None:
    """Seed 49 of the 1,000 km campaign at c2c5ab8 (976.1 km): forced back by an oncoming vehicle while 1.3 m ahead
    of the vehicle it was passing at 6.1 m/s more, the return braked at once to the speed of the vehicle ahead, held
    the AV beside the one it passed through the sideways move, and the two collided. Now it holds its speed until
    that vehicle is the specification's least gap behind, if that comes by the middle of the sideways move and
    braking then still stops short of the vehicle ahead; otherwise it brakes at once, as before."""
    speed, closing = 12.56, 6.1
    lead = Nearest(19.74, closing)
    beside = Nearest(1.26, -closing, behind=True)  # its centre 1.26 m behind the AV's, the AV 6.1 m/s the faster

    def profile(follower: Nearest | None, ahead: Nearest = lead) -> SpeedProfile:
        return fallback.return_profile(around(ahead, follower, slowest_mps=4.9), speed)

    clear_s = (SAFETY.min_gap_m - (1.26 - CAR.length_m)) / closing
    assert clear_s <= TRACKING.lateral_s / 2
    brake_s = closing / MINIMAL_RISK.emergency_decel_mps2
    held = profile(beside)
    assert held.at(clear_s) == pytest.approx(speed)  # the speed it starts at until clear of the vehicle beside
    assert held.at(clear_s + brake_s) == pytest.approx(speed - closing)  # then the vehicle ahead's speed
    closed_m = held.distance_m(clear_s + brake_s) - (speed - closing) * (clear_s + brake_s)
    assert closed_m <= lead.gap_m - SAFETY.min_gap_m - TRACKING.position_m + 1e-9  # still short of it, with margin
    assert profile(None).at(brake_s) == pytest.approx(speed - closing)  # nothing beside: at once, as before
    slower = Nearest(1.26, closing, behind=True)  # the vehicle beside the faster: it passes, the AV brakes at once
    assert profile(slower).at(brake_s) == pytest.approx(speed - closing)
    # not clear by the middle of the sideways move (level with it, 0.5 m/s the faster): braking at once drops the AV
    # behind it, holding would keep it beside it in the lane
    level = Nearest(0.0, -0.5, behind=True)
    assert profile(level).at(brake_s) == pytest.approx(speed - closing)
    # the vehicle ahead too near to wait until clear: at once
    tight = Nearest(CAR.length_m + SAFETY.min_gap_m + TRACKING.position_m + closing * brake_s / 2 + closing * clear_s
                    - 0.1, closing)
    assert profile(beside, tight).at(brake_s) == pytest.approx(speed - closing)


def test_the_fallback_waits_in_the_right_lane_only_while_the_oncoming_lane_leaves_time() -> None:
    def leaves(oncoming: Nearest | None, swept: bool = True) -> bool:
        return fallback.oncoming_leaves_time(around(oncoming=oncoming, swept=swept, oncoming_high_mps=9.0), 7.0, 2.0)

    def need(closing_mps: float) -> float:  # the return's prediction takes the car's envelope (``too_near_after``)
        return SAFETY.required_gap_m(closing_mps + TRACKING.speed_mps) + closing_mps * 2.1 + TRACKING.position_m \
            + CAR.length_m

    closing = 14.0
    need_m = need(closing)
    assert leaves(None)  # none sensed within the front-right sensor's range
    assert not leaves(None, swept=False)  # a dropped sweep
    assert leaves(Nearest(need_m + 1.0, closing)) and not leaves(Nearest(need_m - 1.0, closing))
    # its speed not measured yet (its first two sweeps): the AV's 7 m/s and the bounds' fastest oncoming speed
    unmeasured = 7.0 + 9.0
    need_m = need(unmeasured)
    assert leaves(Nearest(need_m + 1.0, None)) and not leaves(Nearest(need_m - 1.0, None))


def test_the_fallbacks_wait_in_the_right_lane_ends_as_soon_as_a_sensed_oncoming_vehicle_leaves_no_time() -> None:
    """Seed 25 of the reliability campaign (1153285): a fake gap's copy beside the AV held the fallback in the right
    lane for a least wait of ``takeover_s`` while an oncoming vehicle closed from 49 m; the return began 8.6 m from
    it. A sensed oncoming vehicle now ends the wait from its start; a dropped sweep (nothing seen) only after
    ``takeover_s``; nothing holds it past ``return_wait_s``."""
    mr = MINIMAL_RISK

    early = 0.1
    assert mr.ends_wait(early, swept=True, oncoming_leaves_time=False)
    assert not mr.ends_wait(early, swept=True, oncoming_leaves_time=True)
    assert not mr.ends_wait(early, swept=False, oncoming_leaves_time=False)
    assert mr.ends_wait(mr.takeover_s + early, swept=False, oncoming_leaves_time=False)
    assert not mr.ends_wait(mr.return_wait_s, swept=True, oncoming_leaves_time=True)
    assert mr.ends_wait(mr.return_wait_s + early, swept=True, oncoming_leaves_time=True)


DT_S = 1 / 30  # a control step


def never(_speed_mps: float) -> bool:
    return False


def test_the_emergency_brake_reads_the_closing_speed_at_the_cars_own_speed_not_the_hold_speed() -> None:
    """Behind a vehicle at 3 m/s (slower than the bounds let it be: the fallback's case) whose gap breaks the
    specification, fitted while the AV ran at 6 m/s, the fallback brakes to that vehicle's speed and holds it there:
    the closing speed is read at the car's own speed. Read at the hold speed (4.9 m/s), 1.9 m/s of closing would be
    left at the vehicle's speed, and the AV would brake on below it towards a standstill."""
    lead = Nearest(CAR.length_m + 1.0, 3.0, av_mps=6.0)  # 1 m bumper to bumper: nearer than any closing allows
    a = around(lead)
    hold = fallback.in_lane_hold_mps(True, 6.0, 4.9)
    assert hold == 4.9
    assert fallback.brake_command(a, 3.0, 3.0, hold, True, never, DT_S) == pytest.approx(3.0)  # held at its speed
    speed = command = 6.0
    for _ in range(int(3.0 / DT_S)):  # the car follows its command: down at the car's limit, then at its speed
        command = fallback.brake_command(a, speed, command, hold, True, never, DT_S)
        assert command >= 3.0 - MINIMAL_RISK.emergency_decel_mps2 * DT_S - 1e-9
        speed = command
    assert command == pytest.approx(3.0, abs=MINIMAL_RISK.emergency_decel_mps2 * DT_S)
    first = fallback.brake_command(a, 6.0, 6.0, hold, True, never, DT_S)
    assert first == pytest.approx(6.0 - MINIMAL_RISK.emergency_decel_mps2 * DT_S)  # at the car's braking limit


def test_the_emergency_brake_never_raises_its_command_while_the_vehicle_ahead_is_nearer_than_the_specification_allows(
        ) -> None:
    """The car at 6 m/s, above its command at the hold speed (4.9 m/s), 1 m behind a vehicle that does not close on
    it: the gap breaks the specification, and the command stays where it is (taking the vehicle's speed as the target
    raised it towards 6 m/s, past the hold speed, and kept the gap as near as it was); once the gap is wide enough the
    fallback brakes on towards the hold speed as ever."""
    hold = 4.9
    near = around(Nearest(CAR.length_m + 1.0, 0.0, av_mps=6.0))
    assert SAFETY.violated(1.0, 0.0)
    assert fallback.brake_command(near, 6.0, hold, hold, True, never, DT_S) == pytest.approx(hold)
    far = around(Nearest(CAR.length_m + 40.0, 0.0, av_mps=6.0))
    assert fallback.brake_command(far, 6.0, hold, hold, True, never, DT_S) == pytest.approx(hold)
    assert fallback.brake_command(far, 6.0, 6.0, hold, True, never, DT_S) == pytest.approx(
        6.0 - MINIMAL_RISK.decel_mps2 * DT_S)  # on towards the hold speed


def test_the_emergency_brake_brakes_for_a_standstill_when_the_vehicle_aheads_speed_is_not_measured() -> None:
    """Its speed not fitted yet (its first sweeps), the vehicle ahead too near may stand: the target is a standstill,
    whatever the hold speed; far enough, the hold speed, came back up to from below at ``accel_mps2``."""
    near = around(Nearest(CAR.length_m + 1.0, None))
    speed = command = 8.0
    for _ in range(int(3.0 / DT_S)):
        command = fallback.brake_command(near, speed, command, 4.9, True, never, DT_S)
        speed = command
    assert command == 0.0
    far = around(Nearest(CAR.length_m + 200.0, None))
    assert fallback.brake_command(far, 2.0, 2.0, 4.9, True, never, DT_S) == pytest.approx(
        2.0 + MINIMAL_RISK.accel_mps2 * DT_S)
    assert fallback.brake_command(far, 8.0, 8.0, 4.9, True, never, DT_S) == pytest.approx(
        8.0 - MINIMAL_RISK.decel_mps2 * DT_S)


def test_a_gap_at_the_specifications_boundary_is_braked_for_only_once_it_breaks_it() -> None:
    """The emergency brake's trigger is the specification itself (``MinimalRisk.too_near_after`` at 0 s): a gap a
    centimetre wider than the closing speed needs is braked for at ``decel_mps2`` to the hold speed, one a centimetre
    narrower at the car's limit to the vehicle's speed."""
    closing = 2.0
    edge_m = SAFETY.required_gap_m(closing) + CAR.length_m
    speed, hold = 8.0, 4.9
    wide = around(Nearest(edge_m + 0.01, closing))
    narrow = around(Nearest(edge_m - 0.01, closing))
    assert fallback.brake_command(wide, speed, speed, hold, True, never, DT_S) == pytest.approx(
        speed - MINIMAL_RISK.decel_mps2 * DT_S)
    assert fallback.brake_command(narrow, speed, speed, hold, True, never, DT_S) == pytest.approx(
        speed - MINIMAL_RISK.emergency_decel_mps2 * DT_S)


def test_a_return_ends_once_its_move_is_over_where_the_vehicle_ahead_has_come_nearer_than_the_spec_allows() -> None:
    """The return's profile is chosen at its start; a vehicle ahead that then brakes to a standstill (below its lane's
    bounds: following traffic, 10.5 m, seed 4, km 1.63, where the AV kept its speed for the return's last second and
    hit it) closes faster. Once the move is over the return ends for the brake in lane where the gap breaks the
    specification at the closing speed measured now (the emergency brake's own trigger), a centimetre either side."""
    closing = 3.0
    edge_m = SAFETY.required_gap_m(closing) + CAR.length_m
    assert fallback.too_near_now(around(Nearest(edge_m - 0.01, closing)), 4.0)
    assert not fallback.too_near_now(around(Nearest(edge_m + 0.01, closing)), 4.0)
    assert not fallback.too_near_now(around(None), 4.0)  # nothing ahead


def test_the_fallback_opens_the_gap_ahead_only_where_a_decision_needs_it_and_the_vehicle_behind_leaves_room(
        ) -> None:
    """Within the specification but with no safe step in lane for a decision at the hand-back speed (asked of the
    planner), the fallback drives ``open_mps`` below the vehicle ahead's speed; it may open that gap only while the
    vehicle ahead is the nearer of the two and the one behind stays farther than the specification allows at the
    opening's closing speed."""
    lead = Nearest(CAR.length_m + 12.0, 0.0)  # at the AV's speed, 12 m on: within the specification
    asked: list[float] = []

    def needed(speed_mps: float) -> bool:
        asked.append(speed_mps)
        return True

    hold = 4.9
    slow_mps = hold - 2.0 * MINIMAL_RISK.open_mps  # the AV and the vehicle ahead, slower than the hold speed
    command = fallback.brake_command(around(lead), slow_mps, slow_mps, hold, True, needed, DT_S)
    assert asked == [pytest.approx(MINIMAL_RISK.handback_mps(slow_mps, hold))]
    assert command == pytest.approx(slow_mps - MINIMAL_RISK.decel_mps2 * DT_S)  # down towards open_mps below it
    assert fallback.brake_command(around(lead), slow_mps, slow_mps, hold, True, never, DT_S) == pytest.approx(
        slow_mps + MINIMAL_RISK.accel_mps2 * DT_S)  # not needed: up towards the hold speed
    at_mps = slow_mps - MINIMAL_RISK.open_mps  # opened: held there
    assert fallback.brake_command(around(Nearest(CAR.length_m + 12.0, -MINIMAL_RISK.open_mps)), at_mps, at_mps, hold,
                                  True, needed, DT_S) == pytest.approx(at_mps)
    behind_far = Nearest(CAR.length_m + 40.0, 0.0, behind=True)
    behind_near = Nearest(CAR.length_m + SAFETY.required_gap_m(MINIMAL_RISK.open_mps) - 0.1, 0.0, behind=True)
    assert fallback.may_open_gap(around(lead, behind_far))
    assert fallback.may_open_gap(around(lead))  # nothing behind
    assert not fallback.may_open_gap(around(lead, behind_near))  # the one behind would come too near
    assert not fallback.may_open_gap(around(lead, Nearest(CAR.length_m + 10.0, 0.0, behind=True)))  # the nearer
    assert not fallback.may_open_gap(around(lead, swept=False)) and not fallback.may_open_gap(around())


def test_a_proved_continuation_brakes_to_its_hold_speed_and_never_speeds_up() -> None:
    """Without ``emergency`` (a proved continuation) the manoeuvre brakes at ``decel_mps2`` to a hold speed no
    faster than the AV already is, reads no vehicle ahead, and never speeds up."""
    lead = around(Nearest(CAR.length_m + 1.0, 5.0))
    assert fallback.in_lane_hold_mps(False, 6.0, 7.0) == 6.0 and fallback.in_lane_hold_mps(False, 6.0, 4.0) == 4.0
    assert fallback.brake_command(lead, 6.0, 6.0, 4.0, False, never, DT_S) == pytest.approx(
        6.0 - MINIMAL_RISK.decel_mps2 * DT_S)
    assert fallback.brake_command(lead, 3.0, 3.0, 4.0, False, never, DT_S) == 3.0
    assert fallback.ramp_mps(3.0, None, 6.0, DT_S) == 3.0


def test_the_fallback_returns_from_the_right_lane_once_the_left_lane_leaves_room_and_waits_at_its_speeds_till_then(
        ) -> None:
    """One control step of the wait: nothing alongside, nothing near ahead after a return, no follower that
    blocks: return now (None); a vehicle alongside: wait, towards ``waiting_mps``; a wait that ends
    (``MinimalRisk.ends_wait``): return regardless."""
    assert fallback.wait_command(around(), 8.0, False, 8.0, DT_S, DT_S) is None
    beside = Nearest(0.0, 0.04, behind=True)  # level with the AV, 0.04 m/s the faster: it drops back behind it
    a = around(follower=beside)
    waiting = fallback.wait_command(a, 6.96, True, 6.96, DT_S, DT_S)
    target = fallback.waiting_mps(a, 6.96, False, True, False)
    assert target == pytest.approx(7.0 - MINIMAL_RISK.open_mps) and waiting is not None
    assert waiting == pytest.approx(max(target, 6.96 - MINIMAL_RISK.emergency_decel_mps2 * DT_S))
    assert fallback.wait_command(a, 6.96, True, 6.96, MINIMAL_RISK.return_wait_s + DT_S, DT_S) is None
    near = around(Nearest(CAR.length_m + 5.0, 3.0))  # a return would end too near it
    assert fallback.wait_command(near, 8.0, False, 8.0, DT_S, DT_S) is not None
    onc = Nearest(30.0, 16.0)
    assert fallback.wait_command(around(Nearest(CAR.length_m + 5.0, 3.0), oncoming=onc), 8.0, False, 8.0, DT_S,
                                 DT_S) is None  # the oncoming lane leaves no time: back now
    assert fallback.alongside((Reading(Lane.LEFT, 1, -MINIMAL_RISK.beside_m + 0.01),))
    assert not fallback.alongside((Reading(Lane.LEFT, 1, -MINIMAL_RISK.beside_m),))
    assert not fallback.alongside((Reading(Lane.LEFT, 1, 0.01),)) and not fallback.alongside(
        (Reading(Lane.RIGHT, 1, -1.0),))


def oncoming_need_m(closing_mps: float, seconds: float) -> float:
    """The least distance (centre to centre) at which an oncoming vehicle closing at ``closing_mps`` leaves the AV
    ``seconds`` and one more sweep (``oncoming_leaves_time``)."""
    return SAFETY.required_gap_m(closing_mps + TRACKING.speed_mps) + closing_mps * (seconds + 1 / SENSORS.sweep_hz) \
        + TRACKING.position_m + CAR.length_m


def test_a_move_out_is_cut_short_when_the_oncoming_lane_would_not_leave_time_for_its_rest_and_a_return() -> None:
    done_s, left_s, closing = 0.4, 1.6, 14.0
    need_m = oncoming_need_m(closing, left_s + fallback.RETURN_S)

    def reverses(a: fallback.Around) -> bool:
        return fallback.reverses(a, (), 7.0, Lane.RIGHT, done_s, left_s)

    assert reverses(around(oncoming=Nearest(need_m - 1.0, closing)))
    assert not reverses(around(oncoming=Nearest(need_m + 1.0, closing)))
    assert not reverses(around())  # nothing oncoming within the sensor's range
    # a vehicle ahead in the left lane, however near, keeps it from going back no more than the fallback from
    # returning: the oncoming lane is the greater danger
    assert reverses(around(lead=Nearest(CAR.length_m + 1.0, 5.0), oncoming=Nearest(need_m - 1.0, closing)))
    assert reverses(around(swept=False))  # a dropped sweep shows nothing of the oncoming lane


@pytest.mark.parametrize("to_lane", [Lane.RIGHT, Lane.LEFT])
def test_a_move_is_cut_short_only_within_its_first_quarter(to_lane: Lane) -> None:
    """Up to ``MinimalRisk.reverse_within_s`` into the move, and not one control step after."""
    danger = (around(oncoming=Nearest(CAR.length_m + 1.0, 14.0)) if to_lane is Lane.RIGHT
              else around(lead=Nearest(CAR.length_m + 1.0, 3.0)))
    within_s = MINIMAL_RISK.reverse_within_s
    lateral_s = TRACKING.lateral_s
    assert fallback.reverses(danger, (), 7.0, to_lane, within_s, lateral_s - within_s)
    assert not fallback.reverses(danger, (), 7.0, to_lane, within_s + DT_S, lateral_s - within_s - DT_S)


def test_a_return_is_cut_short_when_the_left_lane_would_break_the_spec_at_its_end_and_the_oncoming_lane_leaves_time(
) -> None:
    done_s, left_s, closing = 0.5, 1.5, 3.0
    lead_need_m = SAFETY.required_gap_m(closing + TRACKING.speed_mps) + closing * left_s + TRACKING.position_m \
        + CAR.length_m
    near, far = Nearest(lead_need_m - 0.5, closing), Nearest(lead_need_m + 0.5, closing)

    def reverses(a: fallback.Around, readings: tuple[Reading, ...] = ()) -> bool:
        return fallback.reverses(a, readings, 7.0, Lane.LEFT, done_s, left_s)

    assert reverses(around(lead=near)) and not reverses(around(lead=far))
    assert not reverses(around())
    assert reverses(around(), (Reading(Lane.LEFT, 1, -1.0),))  # a vehicle alongside
    assert reverses(around(follower=Nearest(3.0 + CAR.length_m, 1.0, behind=True), react=False))  # one that blocks
    # going back needs the oncoming lane to leave time to move back and return again
    on_closing = 14.0
    on_need_m = oncoming_need_m(on_closing, done_s + fallback.RETURN_S)
    assert reverses(around(lead=near, oncoming=Nearest(on_need_m + 1.0, on_closing)))
    assert not reverses(around(lead=near, oncoming=Nearest(on_need_m - 1.0, on_closing)))
    assert not reverses(around(lead=near, swept=False))  # a dropped sweep shows nothing of it


@pytest.mark.parametrize(("lead", "follower", "beside", "speed_mps"), [
    (Nearest(2.9, 7.57), None, False, 14.57),  # passing the vehicle ahead, centres 2.9 m apart
    (Nearest(17.9, 2.52), Nearest(3.1, -2.52, behind=True), True, 9.52),  # one alongside behind, 3.1 m
])
def test_an_oncoming_vehicle_ends_the_wait_beside_a_left_lane_vehicle_only_once_it_would_come_within_the_least_gap(
        lead: Nearest, follower: Nearest | None, beside: bool, speed_mps: float) -> None:
    """Seeds 86 and 91 of the reliability campaign at 340c9b6 (faults and tracking, 2026-12-06): forced back by an
    oncoming vehicle the specification's time gap no longer left room for, the fallback moved over beside a left-lane
    vehicle (braking to the speed of the one ahead) and hit it. Beside one, the wait now ends only once the oncoming
    vehicle would come within the least gap; with nothing beside, as before."""
    closing = 21.6
    seconds = fallback.RETURN_S + 1 / SENSORS.sweep_hz
    spec_m = SAFETY.required_gap_m(closing + TRACKING.speed_mps) + closing * seconds + TRACKING.position_m \
        + CAR.length_m
    gap_m = SAFETY.min_gap_m + closing * seconds + TRACKING.position_m + CAR.length_m
    assert gap_m < spec_m

    def waits(oncoming_m: float, lead: Nearest | None = lead, follower: Nearest | None = follower,
              beside: bool = beside) -> bool:
        a = around(lead, follower, Nearest(oncoming_m, closing))
        return fallback.wait_command(a, speed_mps, beside, speed_mps, 1.0, DT_S) is not None

    between_m = (gap_m + spec_m) / 2
    assert waits(between_m) and not waits(gap_m - 0.5)
    assert waits(spec_m + 0.5)
    # with nothing beside (the vehicle ahead too near to return behind, but not alongside) the time gap ends it
    far_lead = Nearest(MINIMAL_RISK.beside_m + 0.5, 7.57)
    assert not waits(between_m, far_lead, None, False) and waits(spec_m + 0.5, far_lead, None, False)


def neighbour(behind: bool = False) -> st.SearchStrategy[Nearest | None]:
    """A sensed neighbour in any state: none, not measured yet, or measured at any closing speed, at any distance
    from touching to the sensors' range, fitted at the AV's speed of the last sweep (or without odometry)."""
    measured = st.one_of(st.none(), st.floats(-15.0, 15.0))
    return st.one_of(st.none(), st.builds(
        lambda dx, closing, av: Nearest(dx, closing, (dx,), () if av is None else (0.0,), av, behind),
        st.floats(CAR.length_m, 120.0), measured, st.one_of(st.none(), st.floats(0.0, 15.0))))


@given(lead=neighbour(), follower=neighbour(behind=True), oncoming=neighbour(), swept=st.booleans(),
       react=st.booleans(), speed=st.floats(0.0, 15.0), command=st.floats(0.0, 15.0), beside=st.booleans(),
       waited=st.floats(0.0, 30.0))
@example(lead=None, follower=Nearest(5.0, -1.0, (5.0,), (), None, True), oncoming=None, swept=False, react=False,
         speed=0.0, command=0.0, beside=False, waited=0.0)  # a follower whose fitted speed is below a standstill
def test_the_waiting_fallbacks_command_is_never_negative_and_changes_at_most_as_fast_as_the_car_may_brake_or_speed_up(
        lead: Nearest | None, follower: Nearest | None, oncoming: Nearest | None, swept: bool, react: bool,
        speed: float, command: float, beside: bool, waited: float) -> None:
    """``wait_command`` with any neighbours: it returns, or its next command is a speed (never below a standstill),
    at most ``emergency_decel_mps2`` below and ``accel_mps2`` above the last one per control step."""
    dt = 1 / 30
    a = around(lead, follower, oncoming, swept=swept, react=react)
    after = fallback.wait_command(a, speed, beside, command, waited, dt)
    if after is None:
        return
    assert after >= 0.0
    assert command - MINIMAL_RISK.emergency_decel_mps2 * dt - 1e-9 <= after
    assert after <= command + MINIMAL_RISK.accel_mps2 * dt + 1e-9


@given(lead=neighbour(), follower=neighbour(behind=True), speed=st.floats(0.0, 15.0), command=st.floats(0.0, 15.0),
       hold=st.floats(0.0, 10.0), emergency=st.booleans(), room=st.booleans())
def test_the_brake_in_lane_never_commands_below_a_standstill_and_speeds_up_only_as_the_fallback_towards_its_hold(
        lead: Nearest | None, follower: Nearest | None, speed: float, command: float, hold: float, emergency: bool,
        room: bool) -> None:
    """``brake_command`` with any neighbours: never below a standstill, down by at most ``emergency_decel_mps2`` per
    control step; up only as the fallback (``emergency``), at most ``accel_mps2``, never past the larger of its hold
    speed and the speed it takes the vehicle ahead to have (a vehicle ahead nearer than the specification allows that
    does not close: its speed, which may be above the hold speed); a proved continuation never speeds up."""
    dt = 1 / 30
    after = fallback.brake_command(around(lead, follower), speed, command, hold, emergency, lambda _: room, dt)
    assert after >= 0.0 and after >= command - MINIMAL_RISK.emergency_decel_mps2 * dt - 1e-9
    if emergency:
        ceiling = hold if lead is None else max(hold, speed - lead.closing_mps(speed))
        assert after <= max(command, min(ceiling, command + MINIMAL_RISK.accel_mps2 * dt)) + 1e-9
    else:
        assert after <= command + 1e-9


@given(lead=neighbour(), speed=st.floats(0.0, 15.0), follower_mps=st.floats(MINIMAL_RISK.open_mps + 0.01, 15.0),
       gap=st.floats(0.0, SAFETY.min_gap_m - 0.01), blocks=st.booleans())
def test_beside_a_vehicle_faster_than_the_opening_speed_the_waiting_fallback_never_aims_for_a_standstill(
        lead: Nearest | None, speed: float, follower_mps: float, gap: float, blocks: bool) -> None:
    """``waiting_mps`` (``MinimalRisk``: "never a standstill beside a vehicle faster than ``open_mps``"): a measured
    vehicle alongside behind, nearer than the least gap, faster than ``open_mps``, whatever is ahead (not near enough
    to set a speed of its own): the target is the AV's to pass it or to drop back behind it, never zero."""
    follower = Nearest(CAR.length_m + gap, follower_mps - speed, (CAR.length_m + gap,), (), None, True)
    assert follower.own_mps(speed) == pytest.approx(follower_mps)
    target = fallback.waiting_mps(around(lead, follower), speed, False, True, blocks)
    assert target is not None and target > 0.0
