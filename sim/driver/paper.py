"""The paper's rules in the loop (``PaperDriver``): a decision from the sensors' last sweep plans in its first
action's frame (``sim.driver.plan.plan_in_frame``), executes up to ``LOOP.replan_after_actions`` actions of the plan,
re-plans when a vehicle not in the plan is sensed, when the plan runs out, and (``replan_on_violation``, not in the
paper) as soon as a vehicle deviates from the prediction beyond the tolerance; a re-plan that finds no plan keeps the
plan under way (the paper warns that re-planning mid-manoeuvre abandons manoeuvres that would have succeeded).

The driver holds the rest of the plan under way and reads and reports through its ``PaperHost`` (``sim.driver.host``),
whose ``predicting`` holds a plan's predicted cells against the world as it executes (the simulator's tolerance check,
``sim.tolerance.PlanCheck``: the paper model's prediction is what its re-planning rule speaks of)."""

from __future__ import annotations

from typing import Protocol

from sim.driver import decide
from sim.driver.control import Steps, held_reference, lane_of, lane_y, until_sweep
from sim.driver.host import Counts, Host, start_decision
from sim.driver.plan import Planner, plan_in_frame
from sim.driver.readings import Reading, snapshot
from spec.actions import Action
from spec.errors import ScenarioError
from spec.grid import Grid
from spec.kinds import FailureKind
from spec.motion import action_speed_mps, plan_profiles, reference_offset_m
from spec.physical import LOOP
from spec.state import State


class Prediction(Protocol):
    """A plan's predicted cells held against the world while it executes."""

    def expecting(self, k: int | None) -> None: ...  # the plan's action ``k`` (from 0) is under way (None: none)

    def deviated(self, k: int, action: Action) -> bool: ...  # after action ``k``: a vehicle beyond the tolerance


class PaperTally(Counts, Protocol):
    frame_fallbacks: int  # plans made in the common-speed frame: none was consistent with its own frame


class PaperHost(Host, Protocol):
    """What the paper's driver asks of its host besides every driver's: its counters and the prediction check."""

    @property
    def summary(self) -> PaperTally: ...

    def predicting(self, plan_id: int, seen: tuple[Reading, ...], states: tuple[State, ...]) -> Prediction: ...


class PaperDriver:
    """The paper model's decisions through ``host``, planned by ``planner`` on ``grid``."""

    def __init__(self, host: PaperHost, planner: Planner, grid: Grid, replan_on_violation: bool = True) -> None:
        self.host, self.planner, self.grid = host, planner, grid
        self.replan_on_violation = replan_on_violation
        self.pending: tuple[Action, ...] = ()  # the rest of the plan under way when a re-plan starts

    def decision(self) -> Steps:
        """One decision from the sensors' last sweep (``decide.paper_choice``): the plan, the plan under way, a wait
        in lane, or driving on."""
        h, ex = self.host, self.host.executor
        pending, self.pending = self.pending, ()
        pose, lane = start_decision(h)
        try:
            readings = snapshot(h.sweep)
        except ScenarioError as err:
            h.contain_from((), pose.x_m, lane)
            return (yield from self.sensing_stop(pending, err))
        h.contain_from(readings, pose.x_m, lane)
        try:
            framed = plan_in_frame(self.planner, self.grid, readings, pose.along_mps, lane)
        except ScenarioError as err:
            return (yield from self.sensing_stop(pending, err))
        h.summary.frame_fallbacks += int(framed.fell_back)
        answer, scenario = framed.answer, framed.scenario
        h.planned(answer, scenario, lane)
        act = decide.paper_choice(answer.status, bool(answer.actions), bool(pending),
                                  refused=lambda: h.refused(answer.actions, pending))
        if act is decide.PaperAct.KEEP:
            return (yield from self.keep(pending, FailureKind.PLANNER, answer.status.value,
                                         f"{answer.status.value} for {scenario}"))
        if act is decide.PaperAct.WAIT:
            h.fail(FailureKind.PLANNER, answer.status.value, f"{answer.status.value} for {scenario}")
            h.doing = "waiting without a plan"
            return (yield from ex.holding(LOOP.wait_s, self.grid.speed))
        if act is decide.PaperAct.DRIVE:
            h.doing = "drive (nothing to overtake)"
            ex.reset_reference()
            profile = plan_profiles((Action.DRIVE,), pose.along_mps, self.grid)[0]
            return (yield from ex.acting(Action.DRIVE, profile))
        if act is decide.PaperAct.HOLD:
            h.doing = "driving on in lane (an overtake refused: the tracker holds a contradiction)"
            return (yield from self.hold_a_sweep())
        h.sight(readings, pose.x_m)
        return (yield from self.execute(answer.actions, answer.states, framed.seen, pose.along_mps, framed.frame_mps))

    def sensing_stop(self, pending: tuple[Action, ...], err: ScenarioError) -> Steps:
        """The snapshot could not be read (or made no scenario): the plan under way goes on, else the stop is
        recorded and the AV waits in lane."""
        h = self.host
        if pending:
            return (yield from self.keep(pending, FailureKind.SENSING, err.reason, str(err)))
        h.fail(FailureKind.SENSING, err.reason, str(err))
        h.doing = "waiting after a sensing failure"
        return (yield from h.executor.holding(LOOP.wait_s, self.grid.speed))

    def hold_a_sweep(self) -> Steps:
        """Drive on in lane at the common speed until the next sweep (at least one control step), the position
        reference where ``control.held_reference`` puts it."""
        h, ex = self.host, self.host.executor
        pose = h.pose()
        ex.x_ref_m = held_reference(ex.x_ref_m, pose.x_m)
        if not (yield float(self.grid.speed), lane_y(lane_of(pose.y_m)), 0.0):
            return False
        return (yield from until_sweep(h.swept, ex.v_ref_mps, lane_y(lane_of(h.pose().y_m))))

    def keep(self, pending: tuple[Action, ...], kind: FailureKind, cause: str, detail: str) -> Steps:
        """A re-plan found no plan (or could not use its snapshot) while a model-checked plan was under way:
        go on with that plan, for at most ``replan_after_actions`` actions, then plan again.

        A re-plan mid-manoeuvre sees a new snapshot, where a vehicle near a cell's edge may
        round the other way; "no plan" there does not undo the plan being executed (the paper
        warns that re-planning mid-manoeuvre abandons manoeuvres that would have succeeded).
        Recorded in ``kept_plans`` with its cause; it is a failure only when no plan is under way.
        """
        h, ex = self.host, self.host.executor
        h.kept(kind, cause, detail)
        ex.reset_reference()
        kept = pending[: LOOP.replan_after_actions]
        for k, (action, profile) in enumerate(zip(kept, plan_profiles(kept, h.pose().along_mps, self.grid))):
            h.doing = f"{action.value} (kept plan after {kind.value}: {cause}, step {k + 1} of {len(kept)})"
            if not (yield from ex.acting(action, profile)):
                return False
            h.summary.actions += 1
        self.pending = pending[len(kept):]
        return True

    def execute(self, actions: tuple[Action, ...], states: tuple[State, ...], seen: tuple[Reading, ...],
                speed_mps: float, frame_mps: float) -> Steps:
        """Execute a plan made in the frame of ``frame_mps`` from the car at ``speed_mps`` (the reference starts
        where that frame puts the AV), action by action, its prediction checked after each."""
        h, ex = self.host, self.host.executor
        plan_id = h.summary.plans
        ex.reset_reference(reference_offset_m(speed_mps, frame_mps, action_speed_mps(actions[0], self.grid)))
        check = h.predicting(plan_id, seen, states)
        executed = actions[: LOOP.replan_after_actions]
        for k, (action, profile) in enumerate(zip(executed, plan_profiles(executed, speed_mps, self.grid))):
            h.doing = f"{action.value} (plan {plan_id}, step {k + 1} of {len(actions)})"
            check.expecting(k)
            ok = yield from ex.acting(action, profile)
            check.expecting(None)
            if not ok:
                return False
            h.summary.actions += 1
            deviated = check.deviated(k, action)  # checked (and traced) after every action, whether it re-plans or not
            if (self.replan_on_violation and deviated) or h.sensed_anew():
                h.summary.replans += 1
                self.pending = actions[k + 1:]
                return True
        self.pending = actions[len(executed):]
        return True
