"""The sound model's driver (``SoundDriver``): a decision from the sensors' last sweep (its snapshot, its plan, what it
chooses), the execution of a proved sequence (a committed part and its escape, or a whole plan) while the AV's own
monitor holds, the last decision's proof kept when a decision proves nothing, a decision taken during a sideways move
once a breach ends the decision under way (finishing or undoing the move, proved), the move sent back by the
fallback's rule when neither is, and the fallback's take-over.

The driver holds what one decision leaves the next: the rest of the proved sequence, its reference's speed profiles
and clock, whether it ends in an escape, the proof kept, whether a breach ends the decision under way. It reads and
reports through its ``SoundHost``, the world that runs it (the car's odometry, the sensors' last sweep, the
controller, the drive's clock and bookkeeping: ``sim.simulator.Simulator``), so tests drive it with a scripted host,
without a physics engine. A decision is the control steps it yields (``sim.driver.control.Steps``)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from functools import partial
from typing import Generic, Protocol, TypeVar

from oracle.sound import keep_lane
from sim.driver import decide, fallback, takeover
from sim.driver.control import Steps, lane_y, resumed
from sim.driver.host import Counts, Host, Odometry, lane_now, start_decision
from sim.driver.monitor import Monitor
from sim.driver.nearest import Nearest
from sim.driver.plan import Planner
from sim.driver.readings import Reading, snapshot
from spec.actions import ACTION_RULES, Action
from spec.answers import Answer, Status
from spec.assumptions import Bounds
from spec.errors import ScenarioError
from spec.escapes import MoveWay, move_ways
from spec.grid import Grid
from spec.kinds import FailureKind
from spec.lanes import Lane
from spec.models import ModelKind
from spec.motion import SpeedProfile, plan_profiles
from spec.physical import LOOP, SENSORS
from spec.scenario import Scenario, problem_for

M = TypeVar("M", bound=Monitor)


class Tally(Counts, Protocol):
    """The counters a sound decision adds to besides every decision's (``sim.summary.RunSummary``)."""

    plan_ms: list[float]
    breach_replans: int
    reversed_moves: int
    moves_finished: int
    moves_undone: int
    moves_unproved: int
    keep_lane_steps: int
    minimal_risk_steps: int
    committed_parts: int
    escapes: int
    unsafe_starts: int
    reference_starts: int
    refined_starts: int
    shadowed: int
    sensed_breaches: int


class SoundHost(Host, Protocol[M]):
    """What the sound driver asks of its host besides every driver's: its counters, the monitor of the decision
    under way (``containment``: the host's, which may hold the truth against the same sets), what the fallback knows
    and moves, and the take-over's record."""

    @property
    def summary(self) -> Tally: ...

    @property
    def containment(self) -> M | None: ...

    def view_m(self, readings: tuple[Reading, ...], av_y_m: float) -> float | None: ...

    def where_swept(self) -> tuple[float, float]: ...

    def check_snapshot(self) -> None: ...

    def resume(self, monitor: M) -> None: ...  # the decision under way goes on under an earlier decision's monitor

    def traced(self, step: int, action: Action | None, since_s: float) -> None: ...

    def take_over(self, cause: str, lane: Lane) -> None: ...

    def taking_over(self) -> bool: ...  # a take-over is under way (a breach sensed then does not interrupt it)

    def hand_back(self) -> None: ...


class SoundDriver(Generic[M]):
    """The sound model's decisions, one after another, through ``host`` (``decision``), planned by ``planner`` on
    ``grid`` under the drive's ``bounds`` (the fallback's hold speed is their lowest in the left lane)."""

    def __init__(self, host: SoundHost[M], planner: Planner, grid: Grid, bounds: Bounds | None) -> None:
        self.host, self.planner, self.grid, self.bounds = host, planner, grid, bounds
        self.pending: tuple[Action, ...] = ()  # the rest of the proved sequence under way when a decision starts
        self.pending_profiles: list[SpeedProfile] = []  # the proved reference's speed profile for ``pending``
        self.escape_pending = False  # the sequence under way ends in a proved escape (the commitment semantics)
        self.boundary = (0.0, 0.0)  # when the last action of a proved sequence ended, and its position reference then
        self.proved: M | None = None  # the monitor of the last decision that was executed: what it proved
        self.unsafe_before = False  # the last decision found its start breaking the safety specification
        self.enveloped = False  # a decision's action is under way: the AV is held to its envelope
        self.interrupt = False  # a breach asks the decision under way to end
        #: what a decision taken during a sideways move chose (``hand_over``): it acts once the move is handed over
        self.taken: Callable[[], Steps] | None = None
        self._unproved_move = False  # this move's decisions during it have proved neither way (counted once)
        self._room = False  # whether the fallback opens the gap ahead (``room_needed``), and on which sweep
        self._room_sweep: tuple[Reading, ...] | None = None
        # what the fallback reads: the nearest vehicles sensed ahead and behind in the left lane, ahead in the oncoming
        # one, followed from sweep to sweep (``on_sweep``)
        self.lead: Nearest | None = None
        self.follower: Nearest | None = None
        self.oncoming: Nearest | None = None
        #: what a take-over reads and moves each control step
        self.cockpit = takeover.Cockpit(lambda: host.pose().along_mps, self.around, lambda: host.sweep or (),
                                        lambda: host.executor.reset_reference())

    def on_sweep(self, travel_m: float) -> None:
        """The sensors swept (``host.sweep``; the AV ``travel_m`` along the road from the drive's start): the AV's own
        monitor reads the sweep against the sets of the decision under way (``Monitor.sense``), and a reading they
        cannot explain ends a decision (not a take-over under way: the next decision ends at once instead); the
        nearest vehicles the fallback reads follow the sweep."""
        h = self.host
        pose, c = h.pose(), h.containment
        if c is not None and c.sense(h.summary.sim_time_s, h.summary.km, pose.x_m, h.sweep or (), h.doing,
                                     self.followed()) is not None:
            h.summary.sensed_breaches += 1
            self.interrupt = self.interrupt or not h.taking_over()
        own, hz = (travel_m, pose.along_mps), SENSORS.sweep_hz
        self.lead = Nearest.after(self.lead, h.sweep, hz, Lane.LEFT, False, *own)
        self.follower = Nearest.after(self.follower, h.sweep, hz, Lane.LEFT, True, *own)
        self.oncoming = Nearest.after(self.oncoming, h.sweep, hz, Lane.RIGHT, False, *own)

    def followed(self) -> bool:
        """``decide.only_followers_behind`` for the action under way."""
        return decide.only_followers_behind(self.host.executor.lane, self.host.executor.lane_due)

    def around(self) -> fallback.Around:
        """What the fallback knows at the last sweep."""
        return fallback.Around(self.lead, self.follower, self.oncoming, self.host.sweep is not None, self.bounds)

    def shift_x(self, dx_m: float) -> None:
        """The world was re-centred by ``dx_m``: the proved reference's place at its boundary moves with it (the
        monitors are the host's to shift, each once)."""
        due_s, ref_m = self.boundary
        self.boundary = (due_s, ref_m + dx_m)

    def _watch(self, readings: tuple[Reading, ...], av_x_m: float, lane: Lane, view_m: float | None = None,
               read: tuple[Reading, ...] | None = None) -> None:
        """The decision's sets from ``readings``: sets that hold the sensing error where they were narrowed from what
        was ``read`` (``refined``), else readings."""
        self.host.contain_from(readings, av_x_m, lane, view_m, read is not None, read)
        self.interrupt = False

    def decision(self) -> Steps:
        """One decision from the sensors' last sweep (the AV's measured speed is the plan's start): a plan, executed
        while the AV's monitor holds; without one, a safe step in lane (``oracle.sound.keep_lane``); without that,
        the fallback (``spec.envelope.MinimalRisk``)."""
        h = self.host
        pose, lane = start_decision(h)
        try:
            readings = snapshot(h.sweep)
        except ScenarioError as err:
            self._watch((), pose.x_m, lane)
            h.fail(FailureKind.SENSING, err.reason, str(err))
            return (yield from self.fallback(f"sensing: {err.reason}"))
        view_m = h.view_m(readings, pose.y_m)
        h.summary.shadowed += int(view_m is not None)
        holds = self.proof_holds(readings, pose)
        sets = self.refined(readings, pose) if holds else None
        seen = readings if sets is None else sets
        self._watch(seen, pose.x_m, lane, view_m, read=None if sets is None else readings)
        h.check_snapshot()  # the snapshot itself: sensed farther off than the error bound, or unknown
        start = self.reference_start(pose) if holds else None
        ahead_m, speed_mps = (0.0, pose.along_mps) if start is None else (pose.x_m - start[0], start[1])
        try:
            scenario = self.moving(self.planner.scenario(seen, lane, speed_mps, view_m, ahead_m, sets is not None,
                                                         start is not None))
        except ScenarioError as err:
            h.fail(FailureKind.SENSING, err.reason, str(err))
            return (yield from self.fallback(f"sensing: {err.reason}"))
        h.summary.reference_starts += int(start is not None)
        answer = self.planner.plan(scenario)
        h.planned(answer, scenario, lane)
        act = self.choice(answer, scenario, readings, pose, speed_mps, start is not None, holds)
        if not (yield from self.while_planning()):
            return False
        return (yield from act())

    def proof_holds(self, readings: tuple[Reading, ...], pose: Odometry) -> bool:
        """Whether the proof of the last decision executed still holds on this snapshot (``readings``, the AV at
        ``pose``): its monitor has sensed no breach, nor does this sweep show one (``Monitor.sense``, which records one
        it finds). Without that proof (none yet, or a take-over or a move sent back since) there is nothing to hold."""
        h = self.host
        return self.proved is not None and self.proved.sensed is None and self.proved.sense(
            h.summary.sim_time_s, h.summary.km, pose.x_m, readings, h.doing, self.followed()) is None

    def refined(self, readings: tuple[Reading, ...], pose: Odometry) -> tuple[Reading, ...] | None:
        """The snapshot's ``readings`` as the sets the last proof, which still holds, narrows them to
        (``Monitor.refine``): the decision plans, and its monitor watches, against what both say of each vehicle.
        None: the proof narrows none of them."""
        assert self.proved is not None
        sets = self.proved.refine(readings, self.host.summary.sim_time_s, pose.x_m)
        self.host.summary.refined_starts += int(sets is not None)
        return sets

    def reference_start(self, pose: Odometry) -> tuple[float, float] | None:
        """Where and how fast a decision whose last proof holds (``proof_holds``) starts its plan on that proof's
        reference, which the car runs on (``decide.plan_start``); None: at the car."""
        ex = self.host.executor
        assert self.proved is not None
        return decide.plan_start(pose.x_m, pose.along_mps, ex.x_ref_m, ex.v_ref_mps, self.proved.sound.tracking)

    def moving(self, scenario: Scenario, left_s: float | None = None) -> Scenario:
        """``scenario`` with the sideways move under way stated (``Sound.sideways_s``): ``left_s`` of it, or what is
        left of the one a decision took over (``Controls.sideways``); unchanged without one."""
        if left_s is None:
            left_s = 0.0 if self.host.executor.sideways is None else self.host.executor.sideways.left_s
        if not left_s or scenario.sound is None:
            return scenario
        return replace(scenario, sound=replace(scenario.sound, sideways_s=left_s))

    def choice(self, answer: Answer, scenario: Scenario, readings: tuple[Reading, ...], pose: Odometry,
               speed_mps: float, on_reference: bool, holds: bool) -> Callable[[], Steps]:
        """What a decision does, chosen when its snapshot (``readings``, the AV at ``pose``) was taken
        (``decide.choose``): the plan (from ``speed_mps``, on the proved reference or at the car), a step in lane, what
        the last decision proved (while it ``holds``: ``proof_holds``), or the fallback; it acts once the planner's
        time is over (``while_planning``)."""
        h = self.host
        unsafe_before, self.unsafe_before = self.unsafe_before, answer.status is Status.UNSAFE_START
        if answer.status is Status.UNSAFE_START:  # an assumption broke before the snapshot: counted, no failure
            h.summary.unsafe_starts += 1
        elif decide.planner_failed(answer.status):
            h.fail(FailureKind.PLANNER, answer.status.value, answer.detail or f"{answer.status.value} for {scenario}")

        def refused() -> bool:  # a refusal drops the rest of the last plan
            if not h.refused(answer.actions, self.pending):
                return False
            self.pending = ()
            return True

        choice = decide.choose(answer.status, bool(answer.actions), refused=refused,
                               step=lambda: keep_lane(problem_for(scenario, ModelKind.FINAL)),
                               unsafe_before=unsafe_before, pending=bool(self.pending), proved_holds=lambda: holds)
        if choice.act is decide.Act.PLAN:
            h.sight(readings, pose.x_m)
            escape = answer.commit.escape if answer.commit is not None else None
            if escape is not None:
                h.summary.committed_parts += 1
            return partial(self.execute, answer.actions, speed_mps, f"plan {h.summary.plans}",
                           escape=escape.actions if escape else (), on_reference=on_reference)
        if choice.act is decide.Act.STEP:
            assert choice.step is not None
            h.summary.keep_lane_steps += 1
            h.sight(readings, pose.x_m)
            return partial(self.execute, (choice.step,), speed_mps, f"keeping the lane ({choice.why})",
                           on_reference=on_reference)
        if choice.act is decide.Act.KEEP:
            return partial(self.keep_proved, choice.why)
        return partial(self.fallback, choice.why)

    def while_planning(self) -> Steps:
        """A decision's snapshot ages while the planner runs: the world moves on for ``LOOP.plan_budget_s`` (one
        control step) before the decision acts, the AV keeping its reference speed in its lane; the sound model plans
        for it (its bounds' ``latency_s``: ``spec.sound.Sound.age_m``). The time the planner took on the machine is
        counted apart (``plan_ms``). False on a collision meanwhile."""
        h = self.host
        if not h.doing.startswith("planning ("):  # a decision that did nothing since the last: not nested again
            h.doing = f"planning ({h.doing})"
        return (yield from h.executor.holding(LOOP.plan_budget_s, h.executor.v_ref_mps))

    def keep_proved(self, why: str) -> Steps:
        """No plan and no step from the fresh snapshot (its cells may be coarser than what the last decision knew),
        while the last decision's assumptions still hold: go on with what that decision proved, under its monitor:
        the rest of its plan, or, after its end, its minimal-risk manoeuvre."""
        h = self.host
        assert self.proved is not None
        h.resume(self.proved)
        self.interrupt = False
        pending, self.pending = self.pending, ()
        if pending:
            h.summary.escapes += int(self.escape_pending)
            h.kept(FailureKind.PLANNER, why, "kept the rest of the last plan"
                   + (" and its escape" if self.escape_pending else ""))
            h.sight(h.sweep or (), *h.where_swept())
            # on the last decision's reference and clock: its windows, its position reference, its speed profile; the
            # control steps since its last action ended (the sweep awaited, this decision's planning: the AV held its
            # reference speed) are the kept plan's first
            return (yield from self.run_proved(pending, self.pending_profiles, len(pending), "the last plan, kept",
                                               since=self.boundary))
        h.summary.minimal_risk_steps += 1
        h.doing = f"minimal-risk manoeuvre (the last decision's, {why})"
        self.enveloped = True
        since_s = h.summary.sim_time_s
        try:
            return (yield from self.brake_in_lane(emergency=False))
        finally:
            self.enveloped = False
            h.traced(0, None, since_s)

    def execute(self, actions: tuple[Action, ...], speed_mps: float, what: str,
                escape: tuple[Action, ...] = (), on_reference: bool = False) -> Steps:
        """Execute a decision's actions from the speed it planned with (the reference restarts at the car, or with
        ``on_reference`` runs on from where the proved one stands: ``decide.plan_start``), while its
        monitor holds as the AV senses it; a sensed breach ends it at once (after any sideways move), and the next
        decision re-plans from a fresh snapshot. The decision has sighted what it knew (``Host.sight``). Under the
        commitment semantics ``actions`` are the committed part and ``escape`` the escape's actions proved after it.
        The reference is the proved sequence's, ramps into the escape included: what is left of it is what a decision
        that proves nothing keeps (``keep_proved``)."""
        h = self.host
        if h.containment is not None:
            h.containment.passing((*actions, *escape))
        if not on_reference:
            h.executor.reset_reference()
        self.escape_pending = bool(escape)
        sequence = (*actions, *escape)
        return (yield from self.run_proved(sequence, plan_profiles(sequence, speed_mps, self.grid, to_common=False),
                                           len(actions), what))

    def run_proved(self, sequence: tuple[Action, ...], profiles: list[SpeedProfile], steps: int, what: str,
                   since: tuple[float, float] | None = None) -> Steps:
        """Run the first ``steps`` (at most ``replan_after_actions``) of a proved ``sequence`` along its
        ``profiles``, from where the position reference stands; the rest stays pending for the next decision.
        ``since``: when the sequence was due to start and where its reference stood then (the end of the action
        before it); the control steps since went by at the reference speed the AV held, so the reference is put where
        the proof's is now and goes on on the proof's clock."""
        h, ex = self.host, self.host.executor
        h.hand_back()
        self.proved = h.containment
        # a breach sensed while a take-over was under way did not interrupt it; it ends this decision before its step
        self.interrupt = self.interrupt or (h.containment is not None and h.containment.sensed is not None)
        # a breach sensed before the first step (while a take-over was handing back): no step
        executed = 0 if self.interrupt else min(steps, LOOP.replan_after_actions)
        self.pending, self.pending_profiles = sequence[executed:], profiles[executed:]
        skip_s = 0.0
        if executed and since is not None:
            skip_s, ex.x_ref_m = resumed(sequence[0], profiles[0], *since, h.summary.sim_time_s, ex.dt_s)
        self.enveloped = True
        try:
            for k in range(executed):
                action = sequence[k]
                h.doing = f"{action.value} ({what}, step {k + 1} of {steps})"
                self.pending, self.pending_profiles = sequence[k + 1:], profiles[k + 1:]
                since_s = h.summary.sim_time_s
                reversed_before = h.summary.reversed_moves
                self._unproved_move = False
                ran = yield from ex.acting(action, profiles[k], stop=lambda: self.interrupt and h.swept(),
                                           skip_s=skip_s if k == 0 else 0.0, reverse=self.reverses,
                                           hand_over=self.hand_over)
                h.traced(k + 1, action, since_s)
                if not ran:
                    return False
                if self.taken is not None:  # a move handed over is no action done: the decision taken acts
                    break
                if h.summary.reversed_moves == reversed_before:  # a move sent back is no action done
                    h.summary.actions += 1
                    self.boundary = (h.summary.sim_time_s, ex.x_ref_m)
                if self.interrupt:
                    break
                if h.sensed_anew():
                    h.summary.replans += 1
                    return True
        finally:
            self.enveloped = False
        if self.taken is not None:
            taken, self.taken = self.taken, None
            h.summary.breach_replans += 1
            if not (yield from self.while_planning()):
                return False
            return (yield from taken())
        if not self.interrupt:
            return True
        h.summary.breach_replans += 1
        return True

    def hand_over(self, to_lane: Lane, done_s: float, left_s: float) -> Lane | None:
        """A decision taken during a sideways move (``done_s`` of it done, ``left_s`` left) once a breach has ended
        the decision under way, on a sweep: a plan proved from the snapshot with the move under way, each way in the
        order ``spec.escapes.move_ways`` states (finishing it into ``to_lane``, undoing it early enough); a plan with
        no action left to take (the goal holds) takes a safe step in lane, proved with the move too. The lane it
        goes to (the move's rest is the executor's, ``Controls.sideways``; the plan acts after the planner's
        time), or None: neither is proved, and the fallback's rule decides (``reverses``, counted)."""
        h = self.host
        if not (self.interrupt and h.swept()):
            return None
        pose = h.pose()
        try:
            readings = snapshot(h.sweep)
        except ScenarioError:
            return None
        view_m = h.view_m(readings, pose.y_m)
        for way, lane, moving_s in move_ways(to_lane, done_s, left_s):
            try:
                scenario = self.moving(self.planner.scenario(readings, lane, pose.along_mps, view_m), moving_s)
            except ScenarioError:
                break
            answer = self.planner.plan(scenario)
            h.summary.plans += 1
            h.summary.plan_ms.append(answer.elapsed_ms)
            if answer.status is not Status.PLAN or (answer.actions and ACTION_RULES[answer.actions[0]].changes_lane):
                continue
            escape = answer.commit.escape if answer.commit is not None else None
            actions = answer.actions
            if not actions:  # the goal holds already: a safe step in lane, as a decision's plan without actions takes
                step = keep_lane(problem_for(scenario, ModelKind.FINAL))
                if step is None:
                    continue
                actions, escape = (step,), None
                h.summary.keep_lane_steps += 1
            h.decided(lane)
            self._watch(readings, pose.x_m, lane, view_m)
            h.sight(readings, pose.x_m)
            finished = way is MoveWay.FINISH
            h.summary.moves_finished += int(finished)
            h.summary.moves_undone += int(not finished)
            h.summary.committed_parts += int(escape is not None)
            self.taken = partial(self.execute, actions, pose.along_mps,
                                 f"plan {h.summary.plans} (the move {'finished' if finished else 'undone'})",
                                 escape=escape.actions if escape else ())
            return lane
        h.summary.moves_unproved += int(not self._unproved_move)
        self._unproved_move = True
        return None

    def reverses(self, to_lane: Lane, done_s: float, left_s: float) -> bool:
        """Whether the sideways move under way goes back to the lane it left: only once a breach (sensed, or of the
        AV's own envelope) has ended the decision, on a sweep, as ``fallback.reverses`` decides from it
        (``MinimalRisk``'s cut-short move); counted. Nothing of the decision's proof is kept after it: the proof
        covers neither finishing the move nor undoing it, so the next decision has no plan to keep."""
        h = self.host
        if not (self.interrupt and h.swept()):
            return False
        if not fallback.reverses(self.around(), h.sweep or (), h.pose().along_mps, to_lane, done_s, left_s):
            return False
        h.summary.reversed_moves += 1
        h.doing = h.doing.replace(" (", " reversed (", 1)
        self.pending, self.pending_profiles, self.proved, self.escape_pending = (), [], None, False
        return True

    def fallback(self, cause: str) -> Steps:
        """The minimal-risk manoeuvre takes over for ``MINIMAL_RISK.takeover_s`` (the host records the take-over):
        back to the left lane from the right one (a return that ends early, its move over, once the vehicle ahead is
        nearer than the specification allows: ``fallback.too_near_now``), then brake in lane to the hold speed, and
        down to the sensed vehicle ahead's speed while it is nearer than the safety specification allows
        (``brake_in_lane``)."""
        h, ex = self.host, self.host.executor
        lane = lane_now(ex, h.pose())
        h.take_over(cause, lane)
        h.doing = f"fallback ({cause})"
        since_s = h.summary.sim_time_s
        try:
            if lane is Lane.RIGHT:
                if not (yield from takeover.awaiting_room(self.cockpit, lane_y(Lane.RIGHT), ex.dt_s)):
                    return False
                ex.reset_reference()
                if not (yield from ex.acting(Action.LEFT_LANE_CHANGE,
                                             fallback.return_profile(self.around(), h.pose().along_mps),
                                             stop=lambda: fallback.too_near_now(self.around(), h.pose().along_mps))):
                    return False
            self.pending, self.proved = (), None
            return (yield from self.brake_in_lane(emergency=True))
        finally:
            h.traced(0, None, since_s)

    def brake_in_lane(self, emergency: bool) -> Steps:
        """The minimal-risk manoeuvre in the AV's lane (``takeover.braking_in_lane``) towards the hold speed: the
        fallback's (``emergency``), or a proved continuation's (its monitor's ``hold_floor_mps``), which a breach
        ends on a sweep."""
        h, ex = self.host, self.host.executor
        assert self.bounds is not None
        low = self.bounds.same_mps.low_mps
        if not emergency and h.containment is not None:  # the proved manoeuvre's own hold speed
            low = h.containment.hold_floor_mps
        hold = fallback.in_lane_hold_mps(emergency, h.pose().along_mps, low)
        ex.lane_due = ex.lane
        return (yield from takeover.braking_in_lane(self.cockpit, hold, lane_y(ex.lane), ex.dt_s, emergency,
                                                    self.room_needed, lambda: self.interrupt and h.swept()))

    def room_needed(self, speed_mps: float) -> bool:
        """Whether a decision from the last sweep at ``speed_mps`` would find no safe step in lane, where the fallback
        may open the gap ahead (``fallback.brake_command`` asks, once ``fallback.may_open_gap``). Asked of the planner
        once per sweep."""
        h = self.host
        sweep = h.sweep
        if sweep is None:
            return False  # a dropped sweep
        if self._room_sweep is sweep:
            return self._room
        self._room_sweep, self._room = sweep, False
        try:
            scenario = self.moving(self.planner.scenario(sweep, h.executor.lane, speed_mps,
                                                         h.view_m(sweep, h.pose().y_m)))
        except ScenarioError:
            return False
        self._room = keep_lane(problem_for(scenario, ModelKind.FINAL)) is None
        return self._room
