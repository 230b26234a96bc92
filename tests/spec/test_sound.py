"""The sound model's rules: exact extremes, windows that move with time and place, vehicles as intervals, input."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
from hypothesis import given
from hypothesis import strategies as st

from spec.actions import ACTION_RULES, Action
from spec.assumptions import MAX_LATENCY_S, Bounds, SpeedBounds, check_bounds, profile
from spec.envelope import TRACKING, Piece
from spec.errors import OptionError
from spec.grid import COMMON_SPEED_MPS, PAPER_GRID
from spec.lanes import Lane
from spec.motion import action_speed_mps
from spec.safety import Conflict
from spec.sound import (
    EPS_M,
    PHANTOM_NEAREST_M,
    Sound,
    SoundRules,
    SoundState,
    follower_limit_m,
    sound_from,
    sound_from_table,
    sound_to_table,
    vehicles,
)
from spec.windows import sound_table

DEFAULT = Sound(profile("default"))
finite = st.floats(-50.0, 50.0)


def _rules(sound: Sound = DEFAULT, lane: Lane = Lane.LEFT, left: tuple[int, ...] = (), right: tuple[int, ...] = ()
           ) -> SoundRules:
    return SoundRules(sound, lane, left, right, PAPER_GRID, ())


@given(st.floats(0.0, 200.0), st.floats(0.0, 6.0), st.floats(-200.0, 400.0), st.floats(0.0, 20.0),
       st.floats(-6.0, 6.0))
def test_thresholds_are_the_extremes_of_their_conditions_over_a_piece(t0: float, span: float, x0: float, v0: float,
                                                                      acc: float) -> None:
    """Each threshold is the exact extreme over the piece: no sample beats it, and it is reached (to 1e-6 m)."""
    v0 = max(0.0, v0)
    if v0 + acc * span < 0:
        acc = -v0 / span if span > 0 else 0.0
    rules, p = _rules(), Piece(t0, t0 + span, x0, v0, acc)
    s, tr, b = DEFAULT.safety, DEFAULT.tracking, DEFAULT.bounds
    times = [t0 + span * i / 400 for i in range(401)]
    ahead = [p.x(t) - b.same_mps.low_mps * t + tr.position_m + s.vehicle_length_m
             + s.required_gap_m(p.v(t) + tr.speed_mps - b.same_mps.low_mps) for t in times]
    oncoming = [p.x(t) + b.oncoming_mps.high_mps * t + tr.position_m + s.vehicle_length_m
                + s.required_gap_m(p.v(t) + tr.speed_mps + b.oncoming_mps.high_mps) for t in times]
    behind = [p.x(t) - b.same_mps.high_mps * t - tr.position_m - s.vehicle_length_m
              - s.required_gap_m(b.same_mps.high_mps - p.v(t) + tr.speed_mps) for t in times]
    for got, sampled, sign in ((rules._ahead_need(p), ahead, 1), (rules._oncoming_need(p), oncoming, 1),
                               (rules._behind_allow(p), behind, -1)):
        best = max(v * sign for v in sampled) * sign
        assert got[0] * sign >= best * sign - 1e-6
        assert got[0] * sign <= best * sign + 1e-3 * (1 + span)  # the sample grid may miss a vertex by a little
        assert t0 - 1e-9 <= got[1] <= t0 + span + 1e-9


@given(st.lists(st.sampled_from(list(Action)), min_size=1, max_size=6), st.sampled_from(list(Action)))
def test_a_window_is_the_same_wherever_it_starts_once_the_first_ramp_is_over(actions: list[Action],
                                                                            action: Action) -> None:
    """The cached, moved window equals the one computed from the reference there."""
    rules = _rules()
    state = SoundState(Lane.LEFT, 0, 0, 0, 0, None, None)
    for a in actions:
        state = rules.after(state, a)
    moved = rules.window(state, action)
    rules._relative.clear()
    ref = rules.reference(state, action)
    direct = [(seg, [rules._bounded(p) for p in ref.pieces(seg.t0_s, seg.t1_s)])
              for seg in rules._segments(state.lane, ref, action, state.moved)]
    assert len(moved) == len(direct)
    for (seg_a, pieces_a), (seg_b, pieces_b) in zip(moved, direct):
        assert (seg_a.lanes, seg_a.entering_left) == (seg_b.lanes, seg_b.entering_left)
        assert seg_a.t0_s == pytest.approx(seg_b.t0_s) and seg_a.t1_s == pytest.approx(seg_b.t1_s)
        for got, want in zip(pieces_a, pieces_b):
            for field in ("ahead", "oncoming", "behind"):
                assert getattr(got, field)[0] == pytest.approx(getattr(want, field)[0], abs=1e-6)
            assert got.piece.x0_m == pytest.approx(want.piece.x0_m, abs=1e-6)


def test_a_cell_means_anywhere_within_it_widened_by_the_sensing_error() -> None:
    """Vehicles are their cells' extents plus the sensing error either way; phantoms cover the unseen stretch."""
    cars = vehicles(Lane.LEFT, (12,), (20,), PAPER_GRID, DEFAULT)
    e = DEFAULT.bounds.sensing_error_m
    assert (cars[0].lo_m, cars[0].hi_m) == (pytest.approx(31.5 - e), pytest.approx(52.5 + e))
    assert (cars[1].lo_m, cars[1].hi_m) == (pytest.approx(210 - e), pytest.approx(231 + e))
    phantoms = [c for c in cars if c.index is None]
    assert len(phantoms) == 3
    assert all(math.isinf(c.hi_m) if c.lo_m > 0 else math.isinf(c.lo_m) for c in phantoms)
    assert not [c for c in vehicles(Lane.LEFT, (), (), PAPER_GRID, Sound(_bounds(phantoms=False))) if c.index is None]


def _bounds(same: tuple[float, float] = (7.0, 7.0), oncoming: tuple[float, float] = (7.0, 7.0), error: float = 0.0,
            phantoms: bool = True) -> Bounds:
    return Bounds("test", SpeedBounds(*same), SpeedBounds(*oncoming), error, phantoms, "a test")


def test_a_car_just_ahead_in_the_avs_lane_breaks_the_start() -> None:
    """A left-lane vehicle in the cell ahead of an AV in the left lane may be touching it: the start is unsafe, and
    the violation says which vehicle, which conflict and the gaps."""
    rules = _rules(left=(11,))
    found = rules.start_violation(SoundState(Lane.LEFT, 0, 0, 0, 0, None, None))
    assert found is not None and found.conflict is Conflict.AHEAD and found.vehicle.index == 0
    assert found.gap_m < found.required_m
    assert "left_lane[0]" in found.describe()


def test_a_follower_is_no_conflict_at_the_start_but_a_cut_in_is() -> None:
    """A vehicle right behind an AV already in the left lane follows it; moving into the lane in front of it is a
    cut-in (the AV starts in the right lane, the vehicle one cell behind and up to 12 m/s fast)."""
    start_left = SoundState(Lane.LEFT, 0, 0, 0, 0, None, None)
    assert _rules(Sound(_bounds(phantoms=False)), left=(8,)).start_violation(start_left) is None
    at_common = _rules(Sound(_bounds(phantoms=False)), lane=Lane.RIGHT, left=(9,))
    assert at_common.step_violation(SoundState(Lane.RIGHT, 0, 0, 0, 0, None, None), Action.LEFT_LANE_CHANGE) is None
    rules = _rules(Sound(_bounds(same=(7.0, 12.0), phantoms=False)), lane=Lane.RIGHT, left=(9,))
    found = rules.step_violation(SoundState(Lane.RIGHT, 0, 0, 0, 0, None, None), Action.LEFT_LANE_CHANGE)
    assert found is not None and found.conflict is Conflict.CUT_IN


@pytest.mark.parametrize("dx_m,follows", [(-6.0, True), (0.0, True), (1.5 - 2 * EPS_M, True), (1.5 + 0.01, False)])
def test_a_vehicle_that_cannot_be_clear_ahead_follows_and_one_that_can_breaks_the_start(dx_m: float,
                                                                                          follows: bool) -> None:
    """Nothing touches the AV at a snapshot, so a vehicle in its lane that cannot be clear ahead of any position of
    the AV is behind it, however near: measured at ``dx_m`` (centre to centre) with 1.5 m of sensing error and the
    AV's 1.5 m envelope, it can be clear ahead from 1.5 m (4.5 m long cars). One that can is an ``ahead`` conflict
    at the start, too near by far."""
    sound = Sound(_bounds(error=1.5, phantoms=False))
    limit = follower_limit_m(0.0, sound)
    assert limit == pytest.approx(-TRACKING.position_m + sound.safety.vehicle_length_m) == pytest.approx(3.0)
    rules = SoundRules(sound, Lane.LEFT, (10,), (), PAPER_GRID, (), left_m=((dx_m, dx_m),))
    found = rules.start_violation(SoundState(Lane.LEFT, 0, 0, 0, 0, None, None))
    assert (found is None) is follows
    if not follows:  # the gap it can have, nothing touching the AV: none at all, far short of the 2 m required
        assert found is not None and found.conflict is Conflict.AHEAD
        assert found.gap_m == pytest.approx(0.0) and found.required_m >= 2.0


@pytest.mark.parametrize("dx_m,follows", [(-6.0 - 2 * EPS_M, True), (-6.0 + 0.01, False)])
def test_where_followers_keep_their_speed_one_follows_only_with_bumpers_clear_of_every_position_of_the_av(
        dx_m: float, follows: bool) -> None:
    """The car may drift back within its envelope, and a follower that keeps its speed does not brake for it: a vehicle
    nearer than bumpers clear behind the AV's rearmost position (4.5 + 1.5 m behind its centre; the vehicle's interval,
    its reading widened by 1.5 m of sensing error, reaching to ``dx_m``) breaks the start."""
    sound = Sound(replace(_bounds(error=1.5, phantoms=False), followers_react=False))
    assert follower_limit_m(0.0, sound) == pytest.approx(-6.0)
    rules = SoundRules(sound, Lane.LEFT, (9,), (), PAPER_GRID, (), left_m=((dx_m - 1.5, dx_m - 1.5),))
    assert (rules.start_violation(SoundState(Lane.LEFT, 0, 0, 0, 0, None, None)) is None) is follows


@pytest.mark.parametrize("hi_m,start_mps,conflict,gap_m,required_m", [
    (-5.99, None, Conflict.BEHIND, -0.01, 0.0),  # at the common speed no follower closes in: bumpers clear
    (3.0 - 2 * EPS_M, None, Conflict.BEHIND, -9.0, 0.0),  # the last position that cannot be clear ahead
    (-5.99, 5.0, Conflict.BEHIND, -0.01, 5.25),  # slower than a follower may be: the cut-in's gap, 1.5 s x 3.5 m/s
    (3.0, None, Conflict.AHEAD, 0.0, 2.25),  # it can be clear ahead of some position of the AV: ahead
])
def test_a_start_conflict_is_named_by_where_the_vehicle_can_be(hi_m: float, start_mps: float | None,
                                                             conflict: Conflict, gap_m: float,
                                                             required_m: float) -> None:
    """Where followers keep their speed, a vehicle short of bumpers clear behind the AV's rearmost position breaks the
    start. One that cannot be clear ahead of any position of the AV (its interval's front short of 3 m: 4.5 m cars,
    1.5 m envelope) is behind it, a lane keeping its order: ``behind``, its gap from the AV's rearmost position (the
    AV's envelope may reach into it), the cut-in's gap required when the AV is slower than a follower may be. One
    that can be clear ahead is ``ahead``, its gap at least 0."""
    sound = Sound(replace(_bounds(error=1.5, phantoms=False), followers_react=False), start_mps=start_mps)
    rules = SoundRules(sound, Lane.LEFT, (9,), (), PAPER_GRID, (), left_m=((hi_m - 1.5 - 1.0, hi_m - 1.5),))
    found = rules.start_violation(SoundState(Lane.LEFT, 0, 0, 0, 0, None, None))
    assert found is not None and found.conflict is conflict
    assert found.gap_m == pytest.approx(gap_m, abs=1e-6) and found.required_m == pytest.approx(required_m)


@pytest.mark.parametrize("bounds,key", [
    (_bounds(same=(-1.0, 7.0)), "--same-mps"),
    (_bounds(oncoming=(7.0, math.nan)), "--oncoming-mps"),
    (_bounds(same=(8.0, 7.0)), "--same-mps"),
    (_bounds(error=math.inf), "sensing-error-m"),
    (_bounds(error=2000.0), "sensing-error-m"),
    (replace(_bounds(), latency_s=-0.1), "latency-s"),
    (replace(_bounds(), latency_s=math.nan), "latency-s"),
    (replace(_bounds(), latency_s=MAX_LATENCY_S + 0.1), "latency-s"),
])
def test_bad_bounds_are_one_line_naming_the_key(bounds: Bounds, key: str) -> None:
    with pytest.raises(OptionError, match=key):
        check_bounds(bounds)


def test_bad_start_speed_is_bad_input() -> None:
    with pytest.raises(OptionError, match="--av-speed-mps"):
        sound_from(None, "default", av_speed_mps=-3.0)


@pytest.mark.parametrize("view", [0.0, -5.0, 400.0, math.nan, "far"])
def test_a_bad_view_of_the_oncoming_lane_is_bad_input_naming_the_option_or_key(view: object) -> None:
    with pytest.raises(OptionError, match="--oncoming-view-m"):
        sound_from(None, "default", oncoming_view_m=view)
    with pytest.raises(OptionError, match=r"bounds\.oncoming_view_m"):
        sound_from_table({"oncoming_view_m": view})


def test_a_view_of_the_oncoming_lane_moves_only_the_oncoming_phantom_and_reads_back_from_a_file() -> None:
    full = Sound(profile("default"))
    hidden = sound_from(None, "default", oncoming_view_m=23.5)
    assert [p.dx_m for p in full.phantoms()] == [100.0, -100.0, 357.0]
    assert [p.dx_m for p in hidden.phantoms()] == [100.0, -100.0, 23.5]
    assert sound_from_table(sound_to_table(hidden)) == hidden
    assert sound_from(None, "default", oncoming_view_m=357.0).phantoms() == full.phantoms()
    assert sound_from(None, "default", phantoms=False, oncoming_view_m=23.5).phantoms() == ()


def test_without_latency_the_snapshot_is_the_plans_start() -> None:
    """No latency: no age, the sensing error alone, the phantoms where the sensors' views end (what every figure
    before the latency was measured with)."""
    for lane in Lane:
        assert DEFAULT.age_m(lane) == 0.0 and DEFAULT.start_error_m(lane) == DEFAULT.bounds.sensing_error_m
    assert DEFAULT.phantoms() == DEFAULT.bounds.phantom_vehicles()


#: The AV's fastest speed, worked out here from the actions and the envelope: the highest start speed drawn.
AV_TOP_MPS = max(action_speed_mps(a, PAPER_GRID) for a in Action) + TRACKING.speed_mps


@given(st.sampled_from(("paper", "default")), st.floats(0.0, MAX_LATENCY_S), st.sampled_from(list(Lane)),
       st.floats(0.0, 1.0), st.floats(-1.0, 1.0), st.floats(0.0, 1.0), st.one_of(st.none(), st.floats(0.0, 1.0)),
       st.floats(-1.0, 1.0), st.booleans(), st.booleans())
def test_every_vehicle_within_the_bounds_is_inside_its_aged_interval_when_the_plan_starts(
        name: str, latency_s: float, lane: Lane, where: float, error: float, speed: float, start: float | None,
        off: float, measured: bool, from_reference: bool) -> None:
    """A vehicle sensed anywhere in a reading's interval, off by at most the sensing error, driving at any speed of
    its lane's bounds (one whose speed was measured: from a standstill to its own top) while the plan's AV drives
    (the car: within its envelope's speed error of a reference whose speed is within that error of the plan's start
    speed, the car's; the reference, ``from_reference``: at exactly the start speed, its own: ``Sound.aging_mps``),
    is inside the interval widened by ``start_error_m`` when the plan starts ``latency_s`` later; and a vehicle
    beyond a phantom's edge at the snapshot is beyond the aged edge then."""
    start_mps = None if start is None else start * AV_TOP_MPS
    if from_reference:
        off = 0.0
    sound = Sound(replace(profile(name), latency_s=latency_s), start_mps=start_mps, from_reference=from_reference)
    b, lo, hi = sound.bounds, 30.0, 51.0
    bounds = b.speeds(lane)
    top_mps = bounds.high_mps + 3.0 if measured else bounds.high_mps
    v_mps = (speed * top_mps) if measured else bounds.low_mps + speed * (bounds.high_mps - bounds.low_mps)
    av_mps = max(0.0, (float(COMMON_SPEED_MPS) if start_mps is None else start_mps) + 2 * off * TRACKING.speed_mps)
    along_mps = (v_mps if lane is Lane.LEFT else -v_mps) - av_mps  # against the AV
    x0 = lo + where * (hi - lo) + error * b.sensing_error_m
    x = x0 + along_mps * latency_s
    e = sound.start_error_m(lane, top_mps if measured else None)
    assert lo - e - 1e-9 <= x <= hi + e + 1e-9
    for edge, aged in zip(b.phantom_vehicles(), sound.phantoms(), strict=True):
        if edge.lane is lane and not measured:  # a phantom is a vehicle of its lane's bounds
            moved = edge.dx_m + along_mps * latency_s  # at the edge at the snapshot: the nearest it can be
            assert (moved >= aged.dx_m - 1e-9) if edge.dx_m > 0 else (moved <= aged.dx_m + 1e-9)


def test_a_latency_reads_back_from_a_file_and_is_bad_input_out_of_range() -> None:
    aged = sound_from(None, "default", latency_s=0.1)
    assert aged.bounds.latency_s == 0.1 and sound_from_table(sound_to_table(aged)) == aged
    assert "latency 0.1 s" in aged.describe()
    fresh, old = (vehicles(Lane.LEFT, (12,), (), PAPER_GRID, s)[0] for s in (DEFAULT, aged))
    assert (fresh.lo_m - old.lo_m, old.hi_m - fresh.hi_m) == pytest.approx((aged.age_m(Lane.LEFT),) * 2)
    with pytest.raises(OptionError, match=r"bounds\.latency_s"):
        sound_from_table({"latency_s": "soon"})
    with pytest.raises(OptionError, match="--latency-s"):
        sound_from(None, "default", latency_s=math.inf)


@pytest.mark.parametrize("moving_s", [-0.1, TRACKING.lateral_s + 0.01, math.nan, "soon"])
def test_a_bad_sideways_move_is_bad_input_naming_the_option_or_key(moving_s: object) -> None:
    with pytest.raises(OptionError, match="--sideways-s"):
        sound_from(None, "default", sideways_s=moving_s)
    with pytest.raises(OptionError, match=r"bounds\.sideways_s"):
        sound_from_table({"sideways_s": moving_s})


def test_a_sideways_move_reads_back_from_a_file_and_is_stated() -> None:
    moving = sound_from(None, "default", sideways_s=1.25)
    assert moving.sideways_s == 1.25 and sound_from_table(sound_to_table(moving)) == moving
    assert "both lanes for up to 1.25 s" in moving.describe()
    assert "sideways_s" not in sound_to_table(DEFAULT)


@pytest.mark.parametrize("ahead_m", [-TRACKING.position_m - 0.01, TRACKING.position_m + 0.01, math.nan, "near"])
def test_sensors_off_the_reference_beyond_the_envelope_is_bad_input_naming_the_option_or_key(ahead_m: object) -> None:
    with pytest.raises(OptionError, match="--sensors-ahead-m"):
        sound_from(None, "default", sensors_ahead_m=ahead_m)
    with pytest.raises(OptionError, match=r"bounds\.sensors_ahead_m"):
        sound_from_table({"sensors_ahead_m": ahead_m})


@pytest.mark.parametrize("ahead_m", [-TRACKING.position_m, -0.4, 0.7, TRACKING.position_m])
def test_a_plan_from_the_reference_puts_every_phantom_where_the_sensors_view_ended(ahead_m: float) -> None:
    """The phantoms stand at the edges of what the sensors saw: with the sensors ``ahead_m`` ahead of the plan's
    AV (its reference), each is that much farther ahead of it (a phantom behind, that much nearer), aged as before;
    the file reads it back and the model states it."""
    for view in (None, 23.5):
        at_car = sound_from(None, "default", oncoming_view_m=view, latency_s=0.1)
        moved = sound_from(None, "default", oncoming_view_m=view, latency_s=0.1, sensors_ahead_m=ahead_m)
        assert [p.dx_m for p in moved.phantoms()] == pytest.approx([p.dx_m + ahead_m for p in at_car.phantoms()])
        assert [p.lane for p in moved.phantoms()] == [p.lane for p in at_car.phantoms()]
        assert sound_from_table(sound_to_table(moved)) == moved
        assert f"the car stood {ahead_m:g} m ahead of" in moved.describe()
    assert "sensors_ahead_m" not in sound_to_table(DEFAULT)


def test_vehicles_sensed_as_sets_are_widened_by_the_snapshots_age_alone_and_read_back_from_a_file() -> None:
    """``Sound.sensed_sets``: a scenario's extents that hold the sensing error (a snapshot the last proof narrowed)
    start each vehicle within the age alone, in either lane; the file reads it back and the model states it."""
    sound = sound_from(None, "default", latency_s=0.1)
    sets = sound_from(None, "default", latency_s=0.1, sensed_sets=True)
    for lane in Lane:
        assert sets.start_error_m(lane) == pytest.approx(sound.start_error_m(lane) - sound.bounds.sensing_error_m)
        assert sets.start_error_m(lane) == pytest.approx(sound.age_m(lane)) and sound.bounds.sensing_error_m > 0
    assert sound_from_table(sound_to_table(sets)) == sets and "sensed_sets" not in sound_to_table(sound)
    assert "sensed as sets" in sets.describe() and "sensed as sets" not in sound.describe()
    for bad in ("yes", 1):
        with pytest.raises(OptionError, match=r"bounds\.sensed_sets"):
            sound_from_table({"sensed_sets": bad})


def test_a_plan_from_the_reference_ages_its_vehicles_at_the_references_speed_alone() -> None:
    """``Sound.from_reference``: the plan's AV is the reference, which holds the start speed while the snapshot ages,
    so a same-direction vehicle of the paper's profile (every one at 7 m/s) does not move against a reference at
    7 m/s, where against the car it may by twice the envelope's speed error for the latency; the file reads it back,
    the model states it, and anything but true or false names the key."""
    car = sound_from(None, "paper", latency_s=0.1, av_speed_mps=7.0)
    ref = sound_from(None, "paper", latency_s=0.1, av_speed_mps=7.0, from_reference=True)
    assert ref.age_m(Lane.LEFT) == 0.0 and car.age_m(Lane.LEFT) == pytest.approx(0.1 * 2 * TRACKING.speed_mps)
    assert ref.age_m(Lane.RIGHT) == pytest.approx(0.1 * (ref.bounds.oncoming_mps.high_mps + 7.0))
    assert sound_from_table(sound_to_table(ref)) == ref and "from_reference" not in sound_to_table(car)
    assert "the plan's AV the proved reference" in ref.describe()
    with pytest.raises(OptionError, match=r"bounds\.from_reference"):
        sound_from_table({"from_reference": "yes"})


def test_a_phantom_moved_onto_the_av_stays_on_its_side() -> None:
    """An oncoming view ending right ahead of the car, the reference ahead of the car by more: the phantom stays
    ahead of the AV, at the nearest a phantom may be (never past it, never at 0, which Spin reads as none)."""
    moved = sound_from(None, "default", oncoming_view_m=1.0, sensors_ahead_m=-TRACKING.position_m)
    oncoming = [p for p in moved.phantoms() if p.lane is Lane.RIGHT]
    assert [p.dx_m for p in oncoming] == [PHANTOM_NEAREST_M]


def _windows_along(rules: SoundRules, actions: tuple[Action, ...]) -> list[tuple[float, float, frozenset[Lane], bool]]:
    """Every segment a sequence's proof checks: each step's window, then the continuation's."""
    state, out = SoundState(rules.lane, 0, 0, 0, 0, None, None), []
    for action in (*actions, None):
        out += [(seg.t0_s, seg.t1_s, seg.lanes, seg.entering_left) for seg, _ in rules.window(state, action)]
        if action is not None:
            state = rules.after(state, action)
    return out


@given(st.lists(st.sampled_from(list(Action)), max_size=3), st.sampled_from(list(Lane)),
       st.floats(0.05, TRACKING.lateral_s), st.sampled_from((None, 3.0, 9.5)))
def test_every_instant_of_a_move_under_way_is_checked_in_both_lanes_and_nothing_after_it_changes(
        actions: list[Action], lane: Lane, moving_s: float, start_mps: float | None) -> None:
    """A sideways move under way at the start puts the AV in both lanes at every instant until it ends, moving into
    the left lane when that is the one it goes to, whatever the plan and however short; from its end on every
    window is the one without the move."""
    still = Sound(profile("default"), start_mps=start_mps)
    moving = replace(still, sideways_s=moving_s)
    if not all(ACTION_RULES[a].from_lane in (None, lane_) for a, lane_ in zip(actions, _lanes(lane, actions),
                                                                               strict=True)):
        return
    with_move = _windows_along(_rules(moving, lane), tuple(actions))
    without = _windows_along(_rules(still, lane), tuple(actions))
    samples = [moving_s * k / 20 for k in range(20)]
    for t in samples:
        covering = [w for w in with_move if w[0] <= t <= w[1] and (w[0] < w[1] or t == w[0])]
        assert covering and all(w[2] == frozenset(Lane) and w[3] == (lane is Lane.LEFT or w[3]) for w in covering)
        assert any(w[3] for w in covering) == (lane is Lane.LEFT or any(
            w[3] for w in without if w[0] <= t <= w[1]))
    end_s = max(w[1] for w in without)
    for t in (moving_s + max(0.0, end_s - moving_s) * (k + 1) / 20 for k in range(20) if end_s > moving_s):
        assert {w[2:] for w in with_move if w[0] <= t <= w[1] and w[0] >= moving_s} == \
            {w[2:] for w in without if w[0] <= t <= w[1]}


def _lanes(lane: Lane, actions: list[Action]) -> list[Lane]:
    """The lane each of ``actions`` starts from."""
    out = []
    for a in actions:
        out.append(lane)
        lane = ACTION_RULES[a].to_lane or lane
    return out


def test_a_start_with_a_move_under_way_is_in_both_lanes_and_a_table_of_it_serves_one_start_lane() -> None:
    moving = Sound(profile("default"), sideways_s=1.0)
    assert _rules(moving, Lane.RIGHT).start_segment().lanes == frozenset(Lane)
    assert _rules(DEFAULT, Lane.RIGHT).start_segment().lanes == frozenset({Lane.RIGHT})
    with pytest.raises(ValueError, match="one start lane"):
        sound_table(moving, PAPER_GRID)
    table = sound_table(moving, PAPER_GRID, lane=Lane.LEFT)
    assert table.starts == (Lane.LEFT,) and {key[0] for key in table.early} <= set(Lane)
    start = table.start[Lane.LEFT].stretches[0]
    assert (start.left, start.right, start.entering) == (True, True, True)
    assert sound_table(DEFAULT, PAPER_GRID, lane=Lane.LEFT) is sound_table(DEFAULT, PAPER_GRID)
