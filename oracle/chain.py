"""The receding-horizon chain against continuous motion: decide from a snapshot, commit, let the world move within
the bounds, decide again from a fresh snapshot, take the last decision's escape while nothing new is proved.

The commitment semantics' safety claim (``spec.escapes``) is about this chain, not one plan: while every assumption
holds and the AV decides at least once per committed part, it never breaks the safety specification. Pure
kinematics, like ``oracle.reach``: a seeded world of true vehicles (``World``) moving within the bounds, each lane's
vehicles on one speed schedule that switches at random instants between speeds of the lane's interval, some of them
beyond the sensors' ranges at the start (the phantoms' vehicles); readings within the sensing error, put into cells
by the discretiser's own rules; the AV exactly on the reference of what it executes (``reach.Path``: the actions,
then the minimal-risk manoeuvre). Every control step every true vehicle is held to the specification
(``reach.instant_breach``); followers brake for the AV where the bounds say followers react.

A ``Policy`` decides. ``COMMITTING`` is the claim; ``NO_ESCAPE`` (commit a safe first step of the paper's plan, with
no escape proved) and ``KEEP_PREDICTED`` (when nothing new is proved, drive on along the last predicted plan instead
of its escape) are what the claim rules out, and the chain finds their violations.
"""

from __future__ import annotations

import enum
import math
import random
from collections.abc import Callable
from dataclasses import dataclass, field, replace

from oracle import reach
from oracle.planner import plan
from spec.actions import Action
from spec.answers import Status, Strategy
from spec.cells import first_platoon, left_cell, oncoming_cell
from spec.errors import ScenarioError
from spec.escapes import Commitment
from spec.grid import Grid
from spec.lanes import Lane
from spec.physical import LOOP, SENSORS
from spec.scenario import Scenario, make_scenario, sensed
from spec.sound import Sound, Vehicle, rear_binds

#: The check's step: the executor's control step (the simulator moves the AV no more often).
DT_S = reach.MOTION_DT_S
#: How often the AV decides again once the actions of the path it follows have run out (the loop's wait).
WAIT_S = LOOP.wait_s
#: The planning horizon of every decision.
HORIZON = 12


@dataclass(frozen=True, slots=True)
class World:
    """True vehicles: where each starts (metres along the road, the AV at 0), and each lane's speed schedule."""

    same_m: tuple[float, ...]
    oncoming_m: tuple[float, ...]
    same_speeds: tuple[tuple[float, float], ...]  # (from time, speed), the first from 0
    oncoming_speeds: tuple[tuple[float, float], ...]
    seed: int  # the readings' noise

    def describe(self) -> str:
        return (f"world seed {self.seed}: same-direction at {[round(x, 1) for x in self.same_m]} m, oncoming at "
                f"{[round(x, 1) for x in self.oncoming_m]} m")


def _schedule(rng: random.Random, low: float, high: float, end_s: float) -> tuple[tuple[float, float], ...]:
    """Speeds within ``[low, high]``, the extremes as likely as any other, switching at exponential instants."""
    steps, t = [(0.0, rng.choice((low, high, rng.uniform(low, high))))], 0.0
    while True:
        t += rng.expovariate(1 / 6.0)
        if t >= end_s:
            return tuple(steps)
        steps.append((t, rng.choice((low, high, rng.uniform(low, high)))))


def random_world(seed: int, sound: Sound, grid: Grid, end_s: float) -> World:
    """A world for the chain: a platoon of one to three same-direction vehicles ahead of the AV (at least two
    cells apart, so that no two readings share a cell), sometimes one behind, and oncoming vehicles from near to far
    beyond the front-right sensor's range, each lane on one schedule within its bounds."""
    rng = random.Random(seed)
    b = sound.bounds
    gap = 2.5 * grid.cell
    lead = rng.uniform(25.0, 90.0)
    same = [lead + k * rng.uniform(gap, gap + 20.0) for k in range(rng.randint(1, 3))]
    if rng.random() < 0.4:
        same.append(-rng.uniform(gap, 80.0))
    oncoming, x = [], rng.uniform(60.0, 500.0)
    while x < SENSORS.right_range_m + (b.oncoming_mps.high_mps + 14.0) * end_s:
        oncoming.append(x)
        x += rng.uniform(max(gap, 60.0), 400.0)
    return World(tuple(sorted(same)), tuple(oncoming), _schedule(rng, b.same_mps.low_mps, b.same_mps.high_mps, end_s),
                 _schedule(rng, b.oncoming_mps.low_mps, b.oncoming_mps.high_mps, end_s), seed)


@dataclass(frozen=True, slots=True)
class Decision:
    """What a policy decided: the actions the AV follows from now (then the minimal-risk manoeuvre), and how many of
    them it is committed to before it decides again."""

    actions: tuple[Action, ...]
    committed: int


Policy = Callable[[Scenario], Decision | None]


def committing(scenario: Scenario) -> Decision | None:
    """The commitment semantics: the committed actions, then their escape (a whole proved plan needs none)."""
    answer = plan(scenario, Strategy.SHORTEST)
    if answer.status is not Status.PLAN or answer.commit is None or not answer.commit.committed:
        return None
    c = answer.commit
    return Decision((*c.committed, *(c.escape.actions if c.escape else ())), len(c.committed))


def keep_predicted(scenario: Scenario) -> Decision | None:
    """Ruled out: the committed actions, then the predicted plan in place of the escape."""
    answer = plan(scenario, Strategy.SHORTEST)
    if answer.status is not Status.PLAN or answer.commit is None or not answer.commit.committed:
        return None
    c = answer.commit
    return Decision((*c.committed, *c.predicted), len(c.committed))


def no_escape(scenario: Scenario) -> Decision | None:
    """Ruled out: the first action of the paper's plan whenever the sound model finds that one step safe, no escape
    proved after it (the AV then goes on with the minimal-risk manoeuvre in whichever lane it is)."""
    from oracle.sound import rules_for, start
    from spec.scenario import problem_for

    paper = plan(replace(scenario, sound=None), Strategy.SHORTEST)
    if paper.status is not Status.PLAN or not paper.actions or paper.model is None:
        return None
    problem = problem_for(scenario, paper.model)
    first = paper.actions[0]
    if rules_for(problem).step_violation(start(problem), first) is not None:
        return None
    return Decision((first,), 1)


class Policies(enum.Enum):
    """The policies the chain drives (``POLICY``)."""

    COMMITTING = "committing"
    NO_ESCAPE = "no escape"
    KEEP_PREDICTED = "keep the predicted plan"


POLICY: dict[Policies, Policy] = {Policies.COMMITTING: committing, Policies.NO_ESCAPE: no_escape,
                                  Policies.KEEP_PREDICTED: keep_predicted}


@dataclass(slots=True)
class Outcome:
    """What a chain did: the first breach (None: none), its decisions, and what it executed."""

    breach: reach.Breach | None = None
    decisions: int = 0
    committed: int = 0  # decisions that committed to actions
    escapes: int = 0  # decision points at which nothing new was proved and the last decision's path went on
    lane_changes_right: int = 0
    executed: list[str] = field(default_factory=list)


def _speed(schedule: tuple[tuple[float, float], ...], t: float) -> float:
    found = schedule[0][1]
    for start_s, speed in schedule:
        if start_s > t:
            break
        found = speed
    return found


def drive(world: World, sound: Sound, grid: Grid, policy: Policy, end_s: float, rng_seed: int | None = None) -> \
        Outcome:
    """Drive the chain for ``end_s`` seconds: decide at every boundary of what the AV follows (every ``WAIT_S`` once
    its actions have run out), execute, check every control step (see the module's docstring)."""
    rng = random.Random(world.seed if rng_seed is None else rng_seed)
    b, length, g_min = sound.bounds, sound.safety.vehicle_length_m, sound.safety.min_gap_m
    cars = ([Vehicle(Lane.LEFT, i, math.nan, math.nan, f"same-direction #{i}") for i in range(len(world.same_m))]
            + [Vehicle(Lane.RIGHT, i, math.nan, math.nan, f"oncoming #{i}") for i in range(len(world.oncoming_m))])
    pos = [*world.same_m, *world.oncoming_m]
    outcome = Outcome()
    lane, x0, v0, t0 = Lane.LEFT, 0.0, grid.speed, 0.0  # the current path's start
    path = reach.Path((), replace(sound, start_mps=v0), grid, lane)
    next_decision, followers = 0.0, {i for i, y in enumerate(pos) if cars[i].lane is Lane.LEFT and y < 0.0}
    was_entering = False
    for k in range(round(end_s / DT_S) + 1):
        t = k * DT_S  # boundaries are whole numbers of control steps: a decision meets its boundary exactly
        tau = t - t0
        x, v = x0 + path.position(tau), path.speed(tau)
        if t >= next_decision - 1e-6:
            lanes, _ = path.occupancy(max(0.0, tau - 1e-6))  # the lane the action ending now ends in
            (current,) = lanes
            decided = _decide(world, sound, grid, policy, rng, current, x, v, pos, cars)
            outcome.decisions += 1
            if decided is None:
                outcome.escapes += 1
                later = [s for s in path.bounds_s if s > tau + 1e-9]
                next_decision = t0 + later[0] if later else t + WAIT_S
            else:
                outcome.committed += 1
                outcome.lane_changes_right += int(decided.actions[0] is Action.RIGHT_LANE_CHANGE)
                outcome.executed.append(f"{t:.1f} s: {', '.join(a.value for a in decided.actions)} "
                                        f"(committed {decided.committed})")
                lane, x0, v0, t0 = current, x, v, t
                path = reach.Path(decided.actions, replace(sound, start_mps=v0), grid, lane)
                next_decision = t0 + path.bounds_s[decided.committed]
                tau = 0.0
        lanes, entering = path.occupancy(tau)
        followers = reach.followers_now(followers, was_entering, entering, lanes, cars, pos, x)
        was_entering = entering
        speeds = [_speed(world.same_speeds if c.lane is Lane.LEFT else world.oncoming_speeds, t) for c in cars]
        rear = [rear_binds(b, v)] * len(cars)
        found = reach.instant_breach(sound, f"chain ({world.describe()})", t, x, v, lanes, entering, rear, cars, pos,
                                     speeds, followers)
        if found is not None:
            outcome.breach = found
            return outcome
        for i, c in enumerate(cars):
            pos[i] += speeds[i] * DT_S if c.lane is Lane.LEFT else -speeds[i] * DT_S
            if i in followers and b.followers_react:  # a follower brakes for the AV: no closer than the least gap
                pos[i] = min(pos[i], x0 + path.position(t + DT_S - t0) - length - g_min)
    return outcome


def _decide(world: World, sound: Sound, grid: Grid, policy: Policy, rng: random.Random, lane: Lane, x: float,
            v: float, pos: list[float], cars: list[Vehicle]) -> Decision | None:
    """A snapshot of the world as the sensors read it, and the policy's decision on it (None: a snapshot no scenario
    holds, or nothing decided)."""
    e = sound.bounds.sensing_error_m
    left: list[tuple[int, float]] = []
    right: list[tuple[int, float]] = []
    for i, c in enumerate(cars):
        dx = pos[i] - x
        if c.lane is Lane.LEFT and abs(dx) <= SENSORS.left_range_m:
            reading = dx + rng.uniform(-e, e)
            left.append((left_cell(reading, lane, grid), reading))
        elif c.lane is Lane.RIGHT and -SENSORS.left_range_m <= dx <= SENSORS.right_range_m:
            reading = dx + rng.uniform(-e, e)
            right.append((oncoming_cell(reading, grid), reading))
    left.sort()
    right.sort()
    cells = [c for c, _ in left]
    try:
        base = make_scenario(lane, cells, [c for c, _ in right], first_platoon(cells, lane, grid), horizon=HORIZON,
                             grid=grid)
        scenario = sensed(base, tuple((r, r) for _, r in left), tuple((r, r) for _, r in right))
    except ScenarioError:
        return None
    return policy(replace(scenario, sound=replace(sound, start_mps=v, sensed_sets=False)))  # readings, not sets


def chain_sound(sound: Sound, most_actions: int = 1) -> Sound:
    """``sound`` under the commitment semantics, committing to at most ``most_actions`` per decision."""
    return replace(sound, commitment=Commitment(most_actions=most_actions))
