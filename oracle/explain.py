"""Why is there no plan? A minimal set of vehicles whose presence makes the overtake impossible.

Each vehicle's collision and goal conditions in the Z3 encoding are guarded by a literal
"vehicle i is present". With every vehicle present and no plan of at most ``horizon``
actions, the unsat core over those literals (for every model the pipeline tries) names
vehicles that suffice to block every plan; deletion then removes each vehicle whose
absence still leaves no plan, so the set is minimal. The interpreter checks the result:
the scenario with only those vehicles has no plan, and removing any one of them yields one.

Removing a vehicle keeps the other vehicles' identity: a removed target lowers the
target count, so the remaining targets are the same vehicles as before.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import z3

from oracle.bmc import Encoding, bounded
from oracle.planner import plan
from spec.answers import Answer, Status, Strategy
from spec.errors import EngineError
from spec.lanes import Lane
from spec.models import ModelKind, models_for
from spec.scenario import Scenario, make_scenario, problem_for, sensed

Vehicle = tuple[Lane, int]  # lane and index in that lane's (ascending) cells


@dataclass(frozen=True, slots=True)
class Explanation:
    """The blocking vehicles, the scenario reduced to them, and the plan each removal allows."""

    scenario: Scenario
    has_plan: bool
    blocking: tuple[Vehicle, ...]
    reduced: Scenario | None
    removals: tuple[tuple[Vehicle, Answer], ...]

    def name(self, vehicle: Vehicle) -> str:
        return vehicle_name(self.scenario, vehicle)


def vehicle_name(scenario: Scenario, vehicle: Vehicle) -> str:
    """A sensed vehicle as people read it: its lane, index, role and cell."""
    lane, i = vehicle
    cells = scenario.left_lane if lane is Lane.LEFT else scenario.right_lane
    kind = "oncoming vehicle" if lane is Lane.RIGHT else "vehicle"
    kind = "target" if lane is Lane.LEFT and i in scenario.target_indices else kind
    return f"{lane.value}_lane[{i}] ({kind} at cell {cells[i]})"


def explain(scenario: Scenario, strategy: Strategy = Strategy.SHORTEST) -> Explanation:
    """Explain a scenario without a plan; a scenario with a plan is reported as such."""
    if scenario.sound is not None:
        raise ValueError("explain: Z3 does not answer the sound model (oracle.why.explain_sound explains it)")
    if plan(scenario, strategy).status is Status.PLAN:
        return Explanation(scenario, True, (), None, ())
    vehicles = [(Lane.LEFT, i) for i in range(len(scenario.left_lane))]
    vehicles += [(Lane.RIGHT, i) for i in range(len(scenario.right_lane))]
    literals = {v: z3.Bool(f"present_{v[0].value}_{v[1]}") for v in vehicles}
    solvers = [_solver(scenario, kind, literals) for kind in models_for(scenario.model)]
    core: set[Vehicle] = set()
    for solver in solvers:
        if solver.check(*literals.values()) != z3.unsat:
            raise EngineError("explain: z3 finds a plan the interpreter does not (engines disagree)")
        named = {str(lit) for lit in solver.unsat_core()}
        core |= {v for v in vehicles if str(literals[v]) in named}
    blocking = [v for v in vehicles if v in core]
    for vehicle in list(blocking):  # deletion: drop every vehicle not needed to block all models
        rest = [literals[v] for v in blocking if v != vehicle]
        if all(s.check(*rest) == z3.unsat for s in solvers):
            blocking.remove(vehicle)
    return _checked(scenario, tuple(blocking), strategy)


def _solver(scenario: Scenario, kind: ModelKind, literals: dict[Vehicle, z3.BoolRef]) -> z3.Solver:
    enc = Encoding(problem_for(scenario, kind), present=literals)
    _, constraints, _, _ = bounded(enc)
    solver = z3.SolverFor("QF_LIA")
    solver.set("unsat_core", True)
    solver.add(*constraints, enc.start_checked, *(term == value for term, value in enc.cells(scenario)))
    return solver


def keep_only(scenario: Scenario, keep: set[Vehicle]) -> Scenario:
    """The scenario with only the vehicles in ``keep`` (targets: those kept among the original targets; the sound
    model's assumptions, if any, unchanged; what the snapshot measured of each kept vehicle, ``left_m`` and
    ``right_m``, and their speeds, kept with it: a vehicle read sharper than its cell stays so)."""
    targets = set(scenario.target_indices)
    left_i = [i for i in range(len(scenario.left_lane)) if (Lane.LEFT, i) in keep]
    right_i = [i for i in range(len(scenario.right_lane)) if (Lane.RIGHT, i) in keep]
    kept_targets = sum(1 for i in targets if (Lane.LEFT, i) in keep)
    reduced = make_scenario(scenario.lane, [scenario.left_lane[i] for i in left_i],
                            [scenario.right_lane[i] for i in right_i], kept_targets, scenario.model, scenario.horizon,
                            grid=scenario.grid)
    measured = sensed(reduced, None if scenario.left_m is None else tuple(scenario.left_m[i] for i in left_i),
                      None if scenario.right_m is None else tuple(scenario.right_m[i] for i in right_i))
    measured = replace(measured, left_mps=None if scenario.left_mps is None else tuple(
        scenario.left_mps[i] for i in left_i), right_mps=None if scenario.right_mps is None else tuple(
        scenario.right_mps[i] for i in right_i))
    return replace(measured, sound=scenario.sound)


def _checked(scenario: Scenario, blocking: tuple[Vehicle, ...], strategy: Strategy) -> Explanation:
    """Check with the interpreter: the blocking set alone has no plan, and each removal yields one."""
    reduced = keep_only(scenario, set(blocking))
    if plan(reduced, strategy).status is Status.PLAN:
        raise EngineError("explain: the interpreter plans with only the blocking vehicles (engines disagree)")
    removals = []
    for vehicle in blocking:
        answer = plan(keep_only(scenario, set(blocking) - {vehicle}), strategy)
        if answer.status is not Status.PLAN:
            raise EngineError(f"explain: removing {vehicle} still leaves no plan: the set is not minimal")
        removals.append((vehicle, answer))
    return Explanation(scenario, False, blocking, reduced, tuple(removals))
