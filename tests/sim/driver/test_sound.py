"""The sound model's driver (``sim.driver.sound.SoundDriver``) with a scripted host: constructed readings, a scripted
controller that counts its control steps and moves its position reference a metre a step, a scripted monitor, and
the drive's clock advanced by the test's own world step; no physics engine."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from types import SimpleNamespace
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from sim.driver.control import Command, Sideways, Steps, perform, resumed
from sim.driver.fallback import Around, in_lane_hold_mps
from sim.driver.monitor import Breach, BreachKind
from sim.driver.readings import Reading
from sim.driver.sound import SoundDriver
from sim.summary import RunSummary
from spec.actions import ACTION_RULES, Action
from spec.answers import Answer, Commit, Status, Strategy
from spec.assumptions import PROFILES
from spec.envelope import MINIMAL_RISK
from spec.errors import ScenarioError
from spec.escapes import ESCAPES
from spec.grid import PAPER_GRID
from spec.kinds import FailureKind
from spec.lanes import Lane
from spec.models import ModelKind
from spec.motion import SpeedProfile, plan_profiles
from spec.scenario import Scenario, make_scenario
from spec.sound import Sound

DT = 0.05  # the scripted controller's control step (s)
STEPS = 4  # its control steps per action
BOUNDS = PROFILES["paper"]
BREACH = Breach(1, 0.0, 0.0, "a sensed left-lane reading at +30.0 m", -4, BreachKind.TOO_SLOW, 2.0, "drive")


class Controls:
    """A scripted controller: ``STEPS`` control steps per action (a metre each), ``stop`` asked after each."""

    def __init__(self) -> None:
        self.lane: Lane = Lane.LEFT
        self.lane_due: Lane | None = Lane.LEFT
        self.x_ref_m, self.v_ref_mps, self.dt_s = 0.0, 7.0, DT
        self.acted: list[tuple[Action, SpeedProfile | None, float]] = []  # each action asked: profile, skip_s
        self.resets = 0
        self.sideways: Sideways | None = None

    def reset_reference(self, ahead_m: float = 0.0) -> None:
        self.resets += 1
        self.x_ref_m = ahead_m

    def acting(self, action: Action, profile: SpeedProfile | None = None, stop: Callable[[], bool] | None = None,
               skip_s: float = 0.0, reverse: Callable[[Lane, float, float], bool] | None = None,
               hand_over: Callable[[Lane, float, float], Lane | None] | None = None) -> Steps:
        self.acted.append((action, profile, skip_s))
        for _ in range(STEPS):
            self.x_ref_m += 1.0
            if not (yield 7.0, 1.75, 0.0):
                return False
            if stop is not None and stop():
                break
        return True

    def holding(self, seconds: float, speed_mps: float) -> Steps:
        for _ in range(max(1, round(seconds / DT))):
            if not (yield speed_mps, 1.75, 0.0):
                return False
        return True


@dataclass
class Monitor:
    """A scripted monitor: the first breach the AV sensed, and the floor its proved manoeuvre brakes to."""

    sensed: Breach | None = None
    hold_floor_mps: float = 5.0
    passed: tuple[Action, ...] | None = None
    sound: Sound = field(default_factory=lambda: Sound(BOUNDS))

    def passing(self, actions: tuple[Action, ...]) -> None:
        self.passed = actions

    def sense(self, *_: object) -> Breach | None:
        return self.sensed

    #: what ``refine`` answers: the readings as sets the proof narrows them to (None: it narrows none)
    narrows: tuple[Reading, ...] | None = None

    def refine(self, *_: object) -> tuple[Reading, ...] | None:
        return self.narrows


@dataclass
class Host:
    """A scripted world that runs the driver: a sweep every control step, the AV at 7 m/s in the left lane; at the
    world's step ``breach_at`` the AV's monitor senses a breach (``SoundDriver.on_sweep``: the decision ends)."""

    executor: Controls = field(default_factory=Controls)
    summary: RunSummary = field(default_factory=lambda: RunSummary(seed=1))
    doing: str = "start-up"
    sweep: tuple[Reading, ...] | None = ()
    containment: Any = None
    next_monitor: Monitor = field(default_factory=Monitor)
    breach_at: int | None = None
    driver: SoundDriver[Any] | None = None
    commands: list[Command] = field(default_factory=list)
    log: list[tuple[str, object]] = field(default_factory=list)

    def pose(self) -> Any:
        return SimpleNamespace(x_m=0.0, y_m=1.75, along_mps=7.0)

    def swept(self) -> bool:
        return True

    def taking_over(self) -> bool:
        return bool(self.reported("take_over")) and not self.reported("hand_back")

    def view_m(self, readings: tuple[Reading, ...], av_y_m: float) -> float | None:
        return None

    def where_swept(self) -> tuple[float, float]:
        return 0.0, self.summary.sim_time_s

    def contain_from(self, readings: tuple[Reading, ...], av_x_m: float, lane: Lane, view_m: float | None = None,
                     sensed_sets: bool = False, read: tuple[Reading, ...] | None = None) -> None:
        self.containment = self.next_monitor
        self.log.append(("contain_from", (tuple(r.interval_m for r in readings), sensed_sets)))

    def resume(self, monitor: Monitor) -> None:
        self.containment = monitor

    def check_snapshot(self) -> None: ...

    def sensed_anew(self) -> bool:
        return False

    def refused(self, actions: tuple[Action, ...], under_way: tuple[Action, ...]) -> bool:
        return False

    def __getattr__(self, name: str) -> Callable[..., None]:
        """Every other report (``decided``, ``planned``, ``sight``, ``fail``, ``kept``, ``traced``, ``take_over``,
        ``hand_back``) is logged."""
        return lambda *args: self.log.append((name, args))

    def reported(self, name: str) -> list[object]:
        return [args for what, args in self.log if what == name]

    def step(self, command: Command) -> bool:
        """The world's step: the clock moves on, and at ``breach_at`` the AV senses a breach."""
        self.commands.append(command)
        self.summary.sim_time_s += DT
        if len(self.commands) == self.breach_at and self.containment is not None and self.driver is not None:
            self.containment.sensed = BREACH
            self.driver.interrupt = True
        return True


def driver_of(host: Host, planner: object = None) -> SoundDriver[Any]:
    host.driver = SoundDriver(host, planner, PAPER_GRID, BOUNDS)  # type: ignore[arg-type]
    return host.driver


def test_a_sensed_breach_ends_the_committed_part_at_once_and_the_decision_is_counted_ended_by_it() -> None:
    """A committed part of two actions and its escape: the monitor senses a breach at the second control step; the
    action under way ends after that step, no other action starts, and nothing of the decision is kept as proved
    (its monitor holds the breach, so a later decision cannot keep it)."""
    host = Host(breach_at=2)
    driver = driver_of(host)
    host.contain_from((), 0.0, Lane.LEFT)
    committed, escape = (Action.ACCELERATE, Action.ACCELERATE), (Action.BRAKE,)
    assert perform(driver.execute(committed, 7.0, "plan 1", escape=escape), host.step)
    assert len(host.commands) == 2 and [a for a, _, _ in host.executor.acted] == [Action.ACCELERATE]
    assert host.summary.breach_replans == 1 and host.summary.actions == 1 and not driver.enveloped
    assert host.next_monitor.passed == (*committed, *escape)  # the passing windows are the whole proved sequence's
    assert driver.proved is host.next_monitor and driver.proved.sensed is BREACH


def test_without_a_breach_the_committed_part_runs_and_the_rest_waits_with_its_reference_for_the_next_decision() -> None:
    host = Host()
    driver = driver_of(host)
    host.contain_from((), 0.0, Lane.LEFT)
    committed, escape = (Action.ACCELERATE,), (Action.BRAKE, Action.DRIVE)
    assert perform(driver.execute(committed, 7.0, "plan 1", escape=escape), host.step)
    profiles = plan_profiles((*committed, *escape), 7.0, PAPER_GRID, to_common=False)
    assert [a for a, _, _ in host.executor.acted] == [Action.ACCELERATE] and host.executor.resets == 1
    assert driver.pending == escape and driver.pending_profiles == profiles[1:] and driver.escape_pending
    assert driver.boundary == (pytest.approx(STEPS * DT), STEPS * 1.0)
    assert host.summary.actions == 1 and host.summary.breach_replans == 0
    assert host.reported("traced") == [(1, Action.ACCELERATE, 0.0)]


@pytest.mark.parametrize(("waited_steps", "recentred_m"), [(0, 0.0), (2, 0.0), (7, 0.0), (2, 1004.0)])
def test_a_kept_escape_resumes_on_its_proofs_clock_and_reference_not_one_restarted_at_the_car(
        waited_steps: int, recentred_m: float) -> None:
    """#61 point 4: a decision that proves nothing keeps the last one's escape on that proof's reference. The proof
    was made for the reference at its snapshot, not one restarted at the car: the kept action starts as far into
    itself as the control steps since the last action's end (the sweep awaited, the planning), its position
    reference where the proof's is then, and the reference is never reset. A world re-centred meanwhile
    (``recentred_m``) moves that place with it."""
    host = Host()
    driver = driver_of(host)
    host.contain_from((), 0.0, Lane.LEFT)
    escape = (Action.BRAKE, Action.DRIVE)
    assert perform(driver.execute((Action.ACCELERATE,), 7.0, "plan 1", escape=escape), host.step)
    due_s, ref_m = driver.boundary
    profiles = list(driver.pending_profiles)
    for _ in range(waited_steps):  # the next decision awaits a sweep and plans, holding the reference speed
        host.step((7.0, 1.75, 0.0))
    host.executor.x_ref_m -= recentred_m  # the world re-centred on the car (``Simulator._recentre``)
    driver.shift_x(-recentred_m)
    ref_m -= recentred_m
    host.containment = Monitor()  # that decision's own sets: no plan, no step, so it keeps the last proof
    resumed_at_s = host.summary.sim_time_s
    assert perform(driver.keep_proved("no plan"), host.step)
    skip_s, x_ref_m = resumed(escape[0], profiles[0], due_s, ref_m, resumed_at_s, DT)
    assert host.executor.acted[1:] == [(escape[0], profiles[0], pytest.approx(skip_s)), (escape[1], profiles[1], 0.0)]
    assert skip_s == pytest.approx(waited_steps * DT)
    # from the proof's reference (a metre a step in the scripted controller), never from the car
    assert host.executor.x_ref_m == pytest.approx(x_ref_m + 2 * STEPS * 1.0)
    assert host.executor.resets == 1  # only the decision that proved it started a reference at the car
    assert host.containment is host.next_monitor  # under the sets the escape was proved against
    assert host.summary.escapes == 1 and host.reported("kept") == [
        (FailureKind.PLANNER, "no plan", "kept the rest of the last plan and its escape")]
    assert driver.pending == () and host.summary.actions == 3


def test_after_a_proved_sequence_ends_a_kept_proof_is_its_minimal_risk_manoeuvre_braking_to_its_own_floor() -> None:
    """Nothing of the last plan left: keeping its proof is its minimal-risk manoeuvre, in lane, braking towards the
    proof's own hold speed (never faster than the AV is), held to the envelope, which a sensed breach ends on a
    sweep."""
    host = Host(breach_at=5)
    driver = driver_of(host)
    driver.proved = Monitor(hold_floor_mps=3.0)
    assert perform(driver.keep_proved("no plan"), host.step)
    assert len(host.commands) == 5 and host.summary.minimal_risk_steps == 1 and not driver.enveloped
    hold = in_lane_hold_mps(False, 7.0, 3.0)
    assert all(speed <= 7.0 for speed, _, _ in host.commands) and host.commands[-1][0] >= hold - 1e-9
    assert host.doing == "minimal-risk manoeuvre (the last decision's, no plan)"
    assert host.executor.lane_due is Lane.LEFT and host.reported("traced") == [(0, None, 0.0)]


class FramePlanner:
    """A scripted planner that proves one drive from every snapshot and remembers where each plan started: its speed,
    and how far ahead of the plan's AV the car's sensors stood (``Sound.sensors_ahead_m``) with the readings seen."""

    def __init__(self) -> None:
        self.asked: list[tuple[float | None, float, tuple[float, ...]]] = []
        self.sets: list[bool] = []  # whether each snapshot's readings were sets (``Sound.sensed_sets``)
        self.on_reference: list[bool] = []  # whether each plan's AV was the proved reference (``from_reference``)

    def scenario(self, readings: tuple[Reading, ...], lane: Lane, speed_mps: float | None = None,
                 oncoming_view_m: float | None = None, sensors_ahead_m: float = 0.0,
                 sensed_sets: bool = False, from_reference: bool = False) -> Scenario:
        self.asked.append((speed_mps, sensors_ahead_m, tuple(r.dx_m for r in readings)))
        self.sets.append(sensed_sets)
        self.on_reference.append(from_reference)
        return replace(make_scenario(lane.value, [], [], 0), sound=Sound(BOUNDS, start_mps=speed_mps))

    def plan(self, scenario: Scenario) -> Answer:
        return Answer(Status.PLAN, ModelKind.FINAL, "scripted", Strategy.SENSIBLE, (Action.DRIVE,), (), 1, 0.5)


@pytest.mark.parametrize(("ref_m", "ref_mps", "before", "from_reference"), [
    (-0.5, 7.2, "plan", True),  # the car 0.5 m ahead of its reference, 0.2 m/s faster: pulled back by 0.6 m/s
    (0.7, 7.0, "plan", True),
    (-0.8, 7.0, "plan", False),  # pulled back by 0.64 m/s: more than the envelope leaves above the car's lag
    (0.0, 7.64, "plan", False),
    (-0.5, 7.2, "breach", False),  # the last decision's monitor sensed a breach: its proof no longer holds
    (-0.5, 7.2, "fallback", False),  # after a take-over: no proved reference to run on
])
def test_a_decision_plans_from_the_proved_reference_the_car_runs_on_while_its_proof_holds(
        ref_m: float, ref_mps: float, before: str, from_reference: bool) -> None:
    """Replanning from the planned state: after a proved plan whose proof still holds, the next decision starts its plan
    where the reference is (the readings, taken from the car, seen from there: the planner moves them and the
    phantoms), at the reference's speed, and runs on that reference, not one restarted at the car, while the car is
    near enough to it (``decide.plan_start``); otherwise, or after a breach or a take-over, at the car."""
    host = Host(sweep=(Reading(Lane.LEFT, 1, 30.0),))
    planner = FramePlanner()
    driver = driver_of(host, planner)
    host.contain_from((), 0.0, Lane.LEFT)
    assert perform(driver.execute((Action.DRIVE,), 7.0, "plan 1"), host.step)  # a proved plan: the car on it
    if before == "breach":
        host.next_monitor.sensed = BREACH
    if before == "fallback":
        host.next_monitor = Monitor()
        assert perform(driver.fallback("no plan"), host.step)
    resets = host.executor.resets
    host.executor.x_ref_m, host.executor.v_ref_mps = ref_m, ref_mps  # the car is at 0 m, 7 m/s (``Host.pose``)
    host.next_monitor = Monitor()
    assert perform(driver.decision(), host.step)
    expected = (ref_mps, -ref_m) if from_reference else (7.0, 0.0)
    assert planner.asked == [(*expected, (30.0,))] and planner.on_reference == [from_reference]
    assert host.summary.reference_starts == int(from_reference)
    assert host.executor.resets == resets + int(not from_reference)
    # the plan executed, its proof the one the next decision may plan from the reference of
    assert [a for a, _, _ in host.executor.acted][-1] is Action.DRIVE and driver.proved is host.next_monitor


@pytest.mark.parametrize("narrows", [True, False])
def test_a_decision_whose_proof_holds_plans_and_watches_against_the_sets_it_narrows_the_readings_to(
        narrows: bool) -> None:
    """SPOT's refinement in the loop: while the last proof holds, its monitor narrows the snapshot's readings to sets
    (``Monitor.refine``); the decision's planner reads those sets (``Sound.sensed_sets``) and its own monitor watches
    the same ones. A proof that narrows nothing leaves the readings as read; a decision after a breach never asks."""
    read, known = Reading(Lane.LEFT, 1, 8.47), Reading(Lane.LEFT, 1, 8.48, (0.0, 1.49))
    host = Host(sweep=(read,))
    planner = FramePlanner()
    driver = driver_of(host, planner)
    host.contain_from((), 0.0, Lane.LEFT)
    assert perform(driver.execute((Action.DRIVE,), 7.0, "plan 1"), host.step)
    proved = driver.proved
    assert isinstance(proved, Monitor)
    proved.narrows = (known,) if narrows else None
    host.next_monitor = Monitor()
    assert perform(driver.decision(), host.step)
    assert driver.proved is host.next_monitor
    seen = known if narrows else read
    assert planner.asked[-1][2] == (seen.dx_m,) and planner.sets[-1] is narrows
    assert host.reported("contain_from")[-1] == ((seen.interval_m,), narrows)
    assert host.summary.refined_starts == int(narrows)
    proved.sensed, proved.narrows = BREACH, (known,)  # the next decision, after a breach: the readings as read
    driver.proved = proved
    assert perform(driver.decision(), host.step)
    assert planner.sets[-1] is False and host.summary.refined_starts == int(narrows)


def test_a_dropped_sweep_is_a_sensing_failure_and_the_fallback_takes_over_for_its_whole_time() -> None:
    host = Host(sweep=None)
    driver = driver_of(host)
    driver.pending, driver.proved = (Action.DRIVE,), Monitor()  # type: ignore[assignment]
    assert perform(driver.decision(), host.step)
    [(kind, reason, _)] = host.reported("fail")  # type: ignore[misc]
    assert (kind, reason) == (FailureKind.SENSING, "the sensors' last sweep never arrived")
    assert host.reported("take_over") == [(f"sensing: {reason}", Lane.LEFT)]
    assert len(host.commands) == round(MINIMAL_RISK.takeover_s / DT)
    assert driver.pending == () and driver.proved is None and host.doing == f"fallback (sensing: {reason})"


def test_the_fallback_asks_the_planner_for_room_ahead_once_per_sweep_and_never_of_a_dropped_one() -> None:
    asked: list[tuple[Reading, ...]] = []

    class Planner:
        def scenario(self, readings: tuple[Reading, ...], *_: object) -> object:
            asked.append(readings)
            raise ScenarioError("snapshot", "two vehicles in one cell", "scripted")

    host = Host(sweep=(Reading(Lane.LEFT, 3, 30.0),))
    driver = driver_of(host, Planner())
    assert not driver.room_needed(7.0) and not driver.room_needed(6.0) and len(asked) == 1
    host.sweep = (Reading(Lane.LEFT, 3, 29.5),)
    assert not driver.room_needed(7.0) and len(asked) == 2
    host.sweep = None
    assert not driver.room_needed(7.0) and len(asked) == 2


@pytest.mark.parametrize(("interrupt", "swept", "oncoming_m", "sent_back"), [
    (True, True, 20.0, True),  # a breach ended the decision, on a sweep, an oncoming vehicle 20 m ahead
    (True, True, None, False),  # nothing oncoming: the move goes on
    (False, True, 20.0, False),  # no breach: the proof covers the move
    (True, False, 20.0, False),  # between sweeps: only a sweep's readings decide
])
def test_a_move_sent_back_keeps_nothing_of_its_decisions_proof(interrupt: bool, swept: bool,
                                                               oncoming_m: float | None, sent_back: bool) -> None:
    """``SoundDriver.reverses``: once a breach has ended a decision, on a sweep, as ``fallback.reverses`` says; then
    nothing of the decision's plan, proof or escape is left for the next decision to keep (the proof covers neither
    finishing the move nor undoing it), and the move is counted. (The paper's rules have no driver: their moves are
    never sent back.)"""
    from sim.driver.nearest import Nearest

    oncoming = None if oncoming_m is None else Nearest(oncoming_m, 14.0)
    host = SimpleNamespace(swept=lambda: swept, sweep=(), pose=lambda: SimpleNamespace(along_mps=7.0),
                           summary=RunSummary(seed=1), doing="right_lane_change (plan 7, step 1 of 3)")
    driver = SoundDriver(host, None, PAPER_GRID, BOUNDS)  # type: ignore[arg-type]
    driver.oncoming = oncoming
    rest = (Action.DRIVE, Action.LEFT_LANE_CHANGE)
    driver.interrupt, driver.pending, driver.pending_profiles = interrupt, rest, [SpeedProfile(7.0, ())] * 2
    driver.proved, driver.escape_pending = Monitor(), True  # type: ignore[assignment]
    assert driver.reverses(Lane.RIGHT, 0.3, 1.7) is sent_back
    assert host.summary.reversed_moves == int(sent_back)
    if sent_back:
        assert driver.pending == () and driver.pending_profiles == [] and driver.proved is None
        assert not driver.escape_pending and host.doing == "right_lane_change reversed (plan 7, step 1 of 3)"
    else:
        assert driver.pending == rest and driver.proved is not None and driver.escape_pending


IN_LANE = (Action.ACCELERATE, Action.DRIVE, Action.BRAKE)


@given(committed=st.lists(st.sampled_from(IN_LANE), min_size=1, max_size=4),
       escape=st.lists(st.sampled_from(IN_LANE), max_size=3),
       breach_at=st.one_of(st.none(), st.integers(min_value=1, max_value=20)))
def test_no_action_runs_on_past_a_sensed_breach_and_what_is_left_is_the_proved_sequences_own_tail(
        committed: list[Action], escape: list[Action], breach_at: int | None) -> None:
    """For any committed part and escape in lane and any control step the monitor senses a breach at: the action
    under way ends at that step, no other starts, the decision is counted as ended by a breach; without one the
    committed part runs whole. Either way what waits for the next decision is the proved sequence's own tail with its
    own reference profiles (a kept escape resumes on them)."""
    host = Host(breach_at=breach_at)
    driver = driver_of(host)
    host.contain_from((), 0.0, Lane.LEFT)
    sequence = (*committed, *escape)
    assert perform(driver.execute(tuple(committed), 7.0, "plan 1", escape=tuple(escape)), host.step)
    whole = len(committed) * STEPS
    broke = breach_at is not None and breach_at <= whole
    ran = -(-breach_at // STEPS) if broke else len(committed)  # type: ignore[operator]
    assert len(host.commands) == (breach_at if broke else whole)
    assert [a for a, _, _ in host.executor.acted] == list(sequence[:ran])
    assert host.summary.breach_replans == int(broke) and host.summary.actions == ran
    profiles = plan_profiles(sequence, 7.0, PAPER_GRID, to_common=False)
    assert driver.pending == sequence[ran:] and driver.pending_profiles == profiles[ran:]
    assert not driver.enveloped


@pytest.mark.parametrize("taking_over", [False, True])
def test_a_sweep_the_decisions_sets_cannot_explain_is_counted_and_ends_the_decision_unless_the_fallback_acts(
        taking_over: bool) -> None:
    """``SoundDriver.on_sweep``: the AV's own monitor reads every sweep; a reading the sets of the decision under way
    cannot explain is counted, and ends the decision, not a take-over under way (the next decision ends at once
    instead: ``run_proved``). The nearest vehicles the fallback reads follow the sweep."""
    host = Host(sweep=(Reading(Lane.LEFT, 3, 30.0), Reading(Lane.RIGHT, 4, 120.0)))
    driver = driver_of(host)
    if taking_over:
        host.take_over("no plan", Lane.LEFT)
    host.containment = Monitor(sensed=BREACH)  # its ``sense`` answers the breach it holds
    driver.on_sweep(0.0)
    assert host.summary.sensed_breaches == 1 and driver.interrupt is not taking_over
    assert driver.lead is not None and driver.lead.dx_m == 30.0 and driver.oncoming is not None
    assert driver.follower is None
    host.containment = Monitor()
    driver.interrupt = False
    driver.on_sweep(1.0)
    assert host.summary.sensed_breaches == 1 and not driver.interrupt
    assert driver.around() == Around(driver.lead, None, driver.oncoming, True, BOUNDS)


class Mover(Controls):
    """The scripted controller, moving sideways too: a lane change's control steps are its sideways move, 0.5 s of it
    each (``MOVE_S`` in ``STEPS``), and after each it asks ``hand_over`` then ``reverse`` as the executor does; a
    move handed over goes on as ``sideways``, what a decision taken during it reads."""

    def __init__(self) -> None:
        super().__init__()
        self.sideways: Sideways | None = None
        self.reversed = False

    def acting(self, action: Action, profile: SpeedProfile | None = None, stop: Callable[[], bool] | None = None,
               skip_s: float = 0.0, reverse: Callable[[Lane, float, float], bool] | None = None,
               hand_over: Callable[[Lane, float, float], Lane | None] | None = None) -> Steps:
        self.acted.append((action, profile, skip_s))
        to_lane = ACTION_RULES[action].to_lane
        for k in range(STEPS):
            self.x_ref_m += 1.0
            if not (yield 7.0, 1.75, 0.0):
                return False
            done_s = (k + 1) * MOVE_S / STEPS
            if to_lane is not None and to_lane is not self.lane and done_s < MOVE_S:
                handed = hand_over(to_lane, done_s, MOVE_S - done_s) if hand_over is not None else None
                if handed is not None:
                    self.sideways = Sideways(1.75, -1.75, MOVE_S, done_s) if handed is to_lane else \
                        Sideways(0.0, 1.75, done_s, 0.0)
                    self.lane = handed
                    return True
                if reverse is not None and reverse(to_lane, done_s, MOVE_S - done_s):
                    self.reversed = True
                    return True
            if stop is not None and stop() and (to_lane is None or done_s >= MOVE_S):
                break
        self.lane = to_lane or self.lane
        return True


MOVE_S = 2.0  # the scripted sideways move


class MovePlanner:
    """A scripted planner: every snapshot the same scenario under the sound model; a plan of ``plan`` where the scenario
    is ``proved_lane`` with a move under way, no plan anywhere else; each question remembered (lane, move left)."""

    def __init__(self, proved_lane: Lane | None, plan: tuple[Action, ...] = (Action.DRIVE,)) -> None:
        self.proved_lane, self.actions = proved_lane, plan
        self.asked: list[tuple[Lane, float]] = []

    def scenario(self, readings: tuple[Reading, ...], lane: Lane, speed_mps: float | None = None,
                 oncoming_view_m: float | None = None, sensors_ahead_m: float = 0.0) -> Scenario:
        return replace(make_scenario(lane.value, [], [], 0), sound=Sound(BOUNDS, start_mps=speed_mps))

    def plan(self, scenario: Scenario) -> Answer:
        assert scenario.sound is not None
        self.asked.append((scenario.lane, scenario.sound.sideways_s))
        proved = scenario.lane is self.proved_lane and scenario.sound.sideways_s > 0
        escape = next(e for e in ESCAPES if e.from_lane is scenario.lane)
        return Answer(Status.PLAN if proved else Status.NO_PLAN, ModelKind.FINAL, "scripted", Strategy.SENSIBLE,
                      self.actions if proved else (), (), 1, 0.5,
                      commit=Commit(self.actions, escape) if proved else None)


def _overtaking(planner: MovePlanner, breach_at: int) -> tuple[Host, SoundDriver[Any]]:
    """A committed lane change out into the right lane, a breach sensed ``breach_at`` control steps into it."""
    host = Host(executor=Mover(), breach_at=breach_at)
    driver = driver_of(host, planner)
    host.contain_from((), 0.0, Lane.LEFT)
    host.next_monitor = Monitor()  # the sets of a decision taken during the move: its own
    assert perform(driver.execute((Action.RIGHT_LANE_CHANGE,), 7.0, "plan 1"), host.step)
    return host, driver


def test_a_breach_during_a_sideways_move_hands_its_rest_to_a_plan_proved_from_the_move_under_way() -> None:
    """#61 point 2: the decision the breach ends leaves a move under way; a decision from that sweep proves a plan
    with the move stated (the lane it goes to, what is left of it), takes the move over there and acts after the
    planner's time, under its own sets; nothing is sent back by the fallback's rule."""
    planner = MovePlanner(Lane.RIGHT)
    host, _ = _overtaking(planner, breach_at=2)
    assert planner.asked == [(Lane.RIGHT, MOVE_S - 2 * MOVE_S / STEPS)]  # finishing, proved: asked first
    mover = host.executor
    assert isinstance(mover, Mover) and mover.lane is Lane.RIGHT and not mover.reversed
    assert mover.sideways == Sideways(1.75, -1.75, MOVE_S, 2 * MOVE_S / STEPS)
    assert [a for a, _, _ in mover.acted] == [Action.RIGHT_LANE_CHANGE, Action.DRIVE]
    assert host.summary.moves_finished == 1 and host.summary.moves_undone == 0 and host.summary.reversed_moves == 0
    assert host.summary.breach_replans == 1 and host.summary.plans == 1 and host.summary.actions == 1
    assert host.reported("decided") == [(Lane.RIGHT,)] and host.containment is host.next_monitor
    assert len(host.commands) == 2 + 1 + STEPS  # the move to the breach, the planner's time, the plan's action


@pytest.mark.parametrize(("breach_at", "undone"), [(1, True), (2, False)])
def test_a_move_is_undone_only_within_the_first_quarter_where_the_move_back_is_measured(breach_at: int,
                                                                                         undone: bool) -> None:
    """Finishing unproved: undoing is asked (back into the lane left, for as long as the move had taken) only up to
    ``MinimalRisk.reverse_within_s`` into it; past that, with neither proved, the fallback's rule decides, counted
    once per move however many sweeps ask."""
    planner = MovePlanner(Lane.LEFT)
    host, _ = _overtaking(planner, breach_at=breach_at)
    done_s = breach_at * MOVE_S / STEPS
    assert done_s <= MINIMAL_RISK.reverse_within_s + 1e-9 or not undone
    assert planner.asked[:2] == [(Lane.RIGHT, MOVE_S - done_s)] + ([(Lane.LEFT, done_s)] if undone else [
        (Lane.RIGHT, MOVE_S - done_s - MOVE_S / STEPS)])
    assert host.summary.moves_undone == int(undone) and host.summary.moves_finished == 0
    assert host.summary.moves_unproved == int(not undone)
    assert isinstance(host.executor, Mover) and (host.executor.sideways is not None) == undone


def test_a_decision_during_a_move_taken_over_plans_with_what_is_left_of_it() -> None:
    host = Host(executor=Mover())
    driver = driver_of(host, MovePlanner(None))
    host.executor.sideways = Sideways(1.75, -1.75, MOVE_S, 1.5)  # type: ignore[attr-defined]
    host.executor.lane = Lane.RIGHT
    scenario = driver.moving(MovePlanner(None).scenario((), Lane.RIGHT, 7.0))
    assert scenario.sound is not None and scenario.sound.sideways_s == pytest.approx(0.5)
    still = MovePlanner(None).scenario((), Lane.RIGHT, 7.0)
    assert driver.moving(still, 0.25).sound.sideways_s == 0.25  # type: ignore[union-attr]
    host.executor.sideways = None  # type: ignore[attr-defined]
    assert driver.moving(still) is still


def test_a_decision_during_a_move_whose_goal_already_holds_takes_a_safe_step_in_lane_proved_with_the_move() -> None:
    """A plan without actions (the goal holds at the start) leaves nothing to execute: the decision takes the step in
    lane a decision without a plan takes (``oracle.sound.keep_lane``), on the scenario with the move stated."""
    host = Host(executor=Mover(), breach_at=2)
    driver = driver_of(host, MovePlanner(Lane.LEFT, plan=()))
    host.executor.lane = Lane.RIGHT  # on the way back into the left lane, on an empty road
    host.contain_from((), 0.0, Lane.RIGHT)
    host.next_monitor = Monitor()
    assert perform(driver.execute((Action.LEFT_LANE_CHANGE,), 7.0, "plan 1"), host.step)
    mover = host.executor
    assert isinstance(mover, Mover) and mover.lane is Lane.LEFT and mover.sideways is not None
    assert [a for a, _, _ in mover.acted] == [Action.LEFT_LANE_CHANGE, Action.DRIVE]
    assert host.summary.moves_finished == 1 and host.summary.keep_lane_steps == 1
