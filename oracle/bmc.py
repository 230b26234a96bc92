"""The Z3 bounded encoding: k decision steps unrolled from spec/, solved incrementally.

State per step: ``right`` (the AV's lane), ``lc`` (lane changes), ``l`` (left-lane
offset: every left-lane vehicle sits at its initial cell + l) and ``o`` (oncoming ticks:
every oncoming vehicle sits at its initial cell - o). All left-lane vehicles move
together and so do all oncoming ones, so these four values are the whole state; each
vehicle's collision and goal conditions are written on its own cell. Every intermediate
oncoming tick gets its own collision check, as in the interpreter.

One decision step is built once, as a template over placeholder states, and every step of the
unrolling is that template with the step's own variables substituted in (one call into Z3, not
thousands of Python-built terms).

``shortest`` adds one step at a time to one solver and asks, under push/pop, whether the
goal holds at step k (having not held before): the first satisfiable k is the shortest
length; all bounds unsatisfiable up to the horizon is a proof of "no plan within the
horizon". ``optimal`` unrolls to the horizon with a symbolic length and minimises the
lexicographic cost term by term on one incremental solver. A solver time-out is "incomplete", never "no plan".
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import z3

from oracle.abstraction import merged, offsets_of
from spec.actions import ACTION_ORDER, ACTION_RULES, Action
from spec.answers import Limits, SearchResult, Status, Strategy
from spec.cost import COST_DOC, COST_TERMS, total_cost
from spec.engines import Engine, register
from spec.lanes import Lane
from spec.rules import behind_line, collision_span, left_path, nearest_span, passed_line
from spec.scenario import Problem
from spec.state import State


@dataclass(frozen=True, slots=True)
class Step:
    """The Z3 variables of one state."""

    right: z3.BoolRef
    lc: z3.ArithRef
    l: z3.ArithRef  # noqa: E741  (the left-lane offset, named as in SPEC.md)
    o: z3.ArithRef


class Encoding:
    """The transition system of one problem as Z3 terms; ``present`` guards each vehicle (explanations)."""

    def __init__(self, problem: Problem, present: dict[tuple[Lane, int], z3.BoolRef] | None = None) -> None:
        self.problem = problem
        scenario = problem.scenario
        self.present = present or {}
        self.steps: list[Step] = []
        self.actions: list[z3.ArithRef] = []
        self.targets = list(scenario.target_indices)
        self.grid = problem.grid
        self.form = offsets_of(problem)
        self.ticks = {a: self.grid.ticks(a) for a in ACTION_ORDER}
        self.right_hits = {t: list(merged([(lo - t, hi) for lo, hi in self.form.right_hits]))
                           for t in {*self.ticks.values(), 0}}  # starting tick counts that meet a danger zone
        start = self.new_step()
        self.initial = z3.And(start.right == (scenario.lane is Lane.RIGHT), start.lc == 0, start.l == 0, start.o == 0,
                              self.safe(start.right, start.l, 0, start.o, 0))
        here, after, action = _placeholder("a"), _placeholder("b"), z3.Int("action")
        self._step_template = (here, action, after, self.transition(here, action, after))
        self._goal_template = (here, self.goal(here))

    def _here(self, lane: Lane, index: int) -> z3.BoolRef | bool:
        return self.present.get((lane, index), True)

    def new_step(self) -> Step:
        k = len(self.steps)
        s = Step(z3.Bool(f"right_{k}"), z3.Int(f"lc_{k}"), z3.Int(f"l_{k}"), z3.Int(f"o_{k}"))
        self.steps.append(s)
        return s

    def bounds(self, k: int) -> z3.BoolRef:
        """Invariants after k actions, implied by the rules but cheap for the solver to use."""
        s = self.steps[k]
        ticks = list(self.ticks.values())
        shifts = [self.grid.left_shift(a) for a in ACTION_ORDER]
        return z3.And(s.lc >= 0, s.lc <= self.problem.rules.max_lane_changes,
                      s.o >= min(ticks) * k, s.o <= max(ticks) * k,
                      s.l >= min(shifts) * k, s.l <= max(shifts) * k)

    def safe(self, right: z3.BoolRef, l_end: z3.ArithRef, shift: int, o_start: z3.ArithRef,
             ticks: int) -> z3.BoolRef:
        """No collision while the left lane shifts by ``shift`` (one cell at a time) to ``l_end``, nor after
        each of ``ticks`` oncoming ticks from ``o_start``."""
        if self.present:
            return self._safe_per_vehicle(right, l_end, shift, o_start, ticks)
        left_ok = [l_end != v for v in sorted(self.form.left_bad_ends(shift))]
        right_ok = [z3.Or(o_start < lo, o_start > hi) for lo, hi in self.right_hits[ticks]]
        return z3.If(right, z3.And(*right_ok, True), z3.And(*left_ok, True))

    def _safe_per_vehicle(self, right: z3.BoolRef, l_end: z3.ArithRef, shift: int, o_start: z3.ArithRef,
                          ticks: int) -> z3.BoolRef:
        """The same condition written per vehicle, each guarded by its presence literal (explanations)."""
        scenario, rules = self.problem.scenario, self.problem.rules
        (l_lo, l_hi), (r_lo, r_hi) = (collision_span(lane, rules, self.grid) for lane in (Lane.LEFT, Lane.RIGHT))
        passed = [(i, c - shift + j) for i, c in enumerate(scenario.left_lane) for j in left_path(shift)]
        left_ok = [z3.Implies(self._here(Lane.LEFT, i), z3.Or(cell + l_end < l_lo, cell + l_end > l_hi))
                   for i, cell in passed]
        right_ok = [z3.Implies(self._here(Lane.RIGHT, i), z3.Or(c - (o_start + j) > r_hi, c - (o_start + j) < r_lo))
                    for i, c in enumerate(scenario.right_lane) for j in range(ticks + 1)]
        return z3.If(right, z3.And(*right_ok, True), z3.And(*left_ok, True))

    def transition(self, a: Step, action_var: z3.ArithRef, b: Step) -> z3.BoolRef:
        """One decision step from ``a`` to ``b`` by the action numbered ``action_var`` (ACTION_ORDER)."""
        rules, options = self.problem.rules, []
        effects = {self._effect(action): action for action in ACTION_ORDER}  # equal conditions built once
        safe = {key: self.safe(b.right, b.l, self.grid.left_shift(action), a.o, self.ticks[action])
                for key, action in effects.items()}
        for index, action in enumerate(ACTION_ORDER):
            rule = ACTION_RULES[action]
            guard = [a.lc < rules.max_lane_changes] if rule.changes_lane else []
            if rule.from_lane is not None:
                guard.append(a.right == (rule.from_lane is Lane.RIGHT))
            lane_after = (rule.to_lane is Lane.RIGHT) if rule.to_lane is not None else a.right
            options.append(z3.And(action_var == index, *guard, b.right == lane_after,
                                  b.lc == a.lc + int(rule.changes_lane), b.l == a.l + self.grid.left_shift(action),
                                  b.o == a.o + self.ticks[action],
                                  safe[self._effect(action)]))
        return z3.Or(*options)

    def _effect(self, action: Action) -> tuple[frozenset[int], int]:
        """What a step's collision condition depends on: the offsets it may not end at, and its ticks."""
        return self.form.left_bad_ends(self.grid.left_shift(action)), self.ticks[action]

    def goal(self, s: Step) -> z3.BoolRef:
        """The problem's goal on the state ``s``, field by field from the GoalRule."""
        goal, scenario, parts = self.problem.goal, self.problem.scenario, []
        if goal.av_lane is not None:
            parts.append(s.right == (goal.av_lane is Lane.RIGHT))
        cells, grid = scenario.left_lane, self.grid
        if goal.targets_behind:
            parts += [z3.Implies(self._here(Lane.LEFT, i), cells[i] + s.l <= behind_line(grid)) for i in self.targets]
        span = nearest_span(goal, grid)
        if span is not None:
            parts.append(self._nearest_within(s, span))
        if goal.oncoming_passed:
            parts += [z3.Implies(self._here(Lane.RIGHT, i), c - s.o <= passed_line(grid))
                      for i, c in enumerate(scenario.right_lane)]
        return z3.And(*parts, True)

    def _nearest_within(self, s: Step, span: tuple[int, int]) -> z3.BoolRef | bool:
        """The nearest present target is within ``span``; false without one."""
        result: z3.BoolRef | bool = False
        for i in reversed(self.targets):
            here, cell = self._here(Lane.LEFT, i), self.problem.scenario.left_lane[i] + s.l
            result = z3.If(here, z3.And(cell >= span[0], cell <= span[1]), result)
        return result

    def extend(self) -> z3.BoolRef:
        """Add one decision step; return its transition constraint (the step template on this step's variables)."""
        a, action_var, b = self.advance()
        here, action, after, template = self._step_template
        return z3.substitute(template, (action, action_var), *_pairs(here, a), *_pairs(after, b))

    def advance(self) -> tuple[Step, z3.ArithRef, Step]:
        """Add the variables of one more decision step: the state it starts from, its action, the state it ends in."""
        a = self.steps[-1]
        action_var = z3.Int(f"a_{len(self.actions) + 1}")
        self.actions.append(action_var)
        return a, action_var, self.new_step()

    def goal_at(self, k: int) -> z3.BoolRef:
        """The goal on the state after k actions (the goal template on its variables)."""
        here, template = self._goal_template
        return z3.substitute(template, *_pairs(here, self.steps[k]))

    def decode(self, model: z3.ModelRef, length: int) -> tuple[tuple[Action, ...], tuple[State, ...]]:
        """The plan of ``length`` actions in ``model`` and the states the model itself assigns along it (the
        pipeline and the trace-equality property compare them with the interpreter's)."""
        actions = tuple(ACTION_ORDER[model.eval(a, model_completion=True).as_long()] for a in self.actions[:length])
        return actions, tuple(self._state(model, k) for k in range(length + 1))

    def _state(self, model: z3.ModelRef, k: int) -> State:
        s, scenario = self.steps[k], self.problem.scenario

        def value(term: z3.ArithRef) -> int:
            return int(model.eval(term, model_completion=True).as_long())

        right = z3.is_true(model.eval(s.right, model_completion=True))
        return State(Lane.RIGHT if right else Lane.LEFT, tuple(c + value(s.l) for c in scenario.left_lane),
                     tuple(c - value(s.o) for c in scenario.right_lane), value(s.lc), k)


def _placeholder(name: str) -> Step:
    """The variables of a template state."""
    return Step(z3.Bool(f"{name}_right"), z3.Int(f"{name}_lc"), z3.Int(f"{name}_l"), z3.Int(f"{name}_o"))


def _pairs(template: Step, step: Step) -> list[tuple[z3.ExprRef, z3.ExprRef]]:
    return [(template.right, step.right), (template.lc, step.lc), (template.l, step.l), (template.o, step.o)]


def shortest(problem: Problem, limits: Limits | None = None) -> SearchResult:
    """The smallest k whose bound is satisfiable, incrementally, or a proof that none is up to the horizon."""
    enc = Encoding(problem)
    solver = z3.SolverFor("QF_LIA")
    started = time.perf_counter()
    solver.add(enc.initial)
    for k in range(problem.horizon + 1):
        reached = z3.Bool(f"goal_{k}")  # checked as an assumption, so learned lemmas carry over
        solver.add(reached == enc.goal_at(k))
        verdict = _check(solver, limits, started, reached)
        if verdict == z3.sat:
            actions, states = enc.decode(solver.model(), k)
            return SearchResult(Status.PLAN, actions, k + 1, f"shortest: bound {k} satisfiable", states)
        if verdict == z3.unknown:
            return SearchResult(Status.INCOMPLETE, (), k, f"z3: {solver.reason_unknown()} at bound {k}")
        if k < problem.horizon:
            solver.add(z3.Not(reached), enc.extend(), enc.bounds(k + 1))
    return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), problem.horizon + 1,
                        f"proved: every bound up to {problem.horizon} is unsatisfiable")


def bounded(enc: Encoding) -> tuple[z3.ArithRef, list[z3.BoolRef], dict[str, z3.ArithRef]]:
    """Plans of any length up to the horizon: a symbolic length N; steps after N repeat the last state. Also the
    plan's cost, term by term (COST_TERMS).

    Everything one step adds (its transition or, from N on, a copy of its state; the goal at N and not before;
    what it adds to each cost term) is one template over placeholder states, the step's number and N, substituted
    once per step."""
    horizon = enc.problem.horizon
    length = z3.Int("length")
    here, action, after, transition = enc._step_template  # the encoding's own templates, on the same placeholders
    goal, k_var = enc._goal_template[1], z3.Int("k")
    reached = z3.And(z3.Implies(length == k_var, goal), z3.Implies(k_var < length, z3.Not(goal)))
    frozen = z3.And(after.right == here.right, after.lc == here.lc, after.l == here.l, after.o == here.o)
    move = z3.And(reached, z3.If(k_var < length, transition, frozen))
    live = k_var + 1 <= length  # the step's action is part of the plan
    brake = ACTION_ORDER.index(Action.BRAKE)
    right_term, brake_term = z3.If(z3.And(live, after.right), 1, 0), z3.If(z3.And(live, action == brake), 1, 0)
    constraints = [enc.initial, length >= 0, length <= horizon]
    rights, brakes = [], []
    for k in range(horizon):
        a, action_var, b = enc.advance()
        pairs = [(k_var, z3.IntVal(k)), (action, action_var), *_pairs(here, a), *_pairs(after, b)]
        constraints.append(z3.substitute(move, *pairs))
        rights.append(z3.substitute(right_term, *pairs))
        brakes.append(z3.substitute(brake_term, *pairs))
    constraints.append(z3.substitute(reached, (k_var, z3.IntVal(horizon)), *_pairs(here, enc.steps[horizon])))
    terms = {"lane_changes": enc.steps[-1].lc, "right_lane_steps": z3.Sum(rights) if rights else z3.IntVal(0),
             "brakes": z3.Sum(brakes) if brakes else z3.IntVal(0), "length": length}
    return length, constraints, terms


def optimal(problem: Problem, limits: Limits | None = None) -> SearchResult:
    """The plan of least cost (COST_DOC) among all plans of at most ``horizon`` actions.

    Lexicographic by successive tightening on one incremental solver: any plan first; then, term by
    term in COST_TERMS order, ask for a plan whose term is below the best value seen (as an
    assumption, so an unsatisfiable bound leaves no trace) until none is, and fix the term there.
    The last model is a least-cost plan. (``z3.Optimize`` answers the same, about twice as slowly.)"""
    started = time.perf_counter()
    enc = Encoding(problem)
    length, constraints, terms = bounded(enc)
    solver = z3.SolverFor("QF_LIA")
    solver.add(*constraints)
    verdict = _check(solver, limits, started)
    if verdict == z3.unsat:
        return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), 1,
                            f"proved: no plan of at most {problem.horizon} actions")
    checks = 1
    if verdict == z3.unknown:
        return _gave_up(solver, checks)
    model = solver.model()
    for name in COST_TERMS:
        best = model.eval(terms[name], model_completion=True).as_long()
        while best > 0:
            below = z3.Bool(f"{name}_below_{best}")
            solver.add(z3.Implies(below, terms[name] < best))
            verdict, checks = _check(solver, limits, started, below), checks + 1
            if verdict == z3.unknown:
                return _gave_up(solver, checks)
            if verdict == z3.unsat:
                break
            model = solver.model()
            best = model.eval(terms[name], model_completion=True).as_long()
        solver.add(terms[name] == best)
    n = model.eval(length).as_long()
    actions, states = enc.decode(model, n)
    cost = dict(zip(COST_TERMS, total_cost(zip(actions, states[1:])), strict=True))  # as the model's states say
    return SearchResult(Status.PLAN, actions, checks, f"optimal under {COST_DOC}", states,
                        {"cost": cost, "cost_order": list(COST_TERMS)})


def _gave_up(solver: z3.Solver, checks: int) -> SearchResult:
    return SearchResult(Status.INCOMPLETE, (), checks, f"z3: {solver.reason_unknown()} after {checks} checks")


def _check(solver: z3.Solver, limits: Limits | None, started: float, *assumptions: z3.BoolRef) -> z3.CheckSatResult:
    """One check within what is left of the time limit. A check cancelled before its limit was interrupted (Ctrl-C,
    or a signal handler cancelling it): that is KeyboardInterrupt, never an "incomplete" answer."""
    limit_s = None if limits is None else limits.timeout_s
    if limit_s is not None:
        left_s = limit_s - (time.perf_counter() - started)
        if left_s <= 0:
            return z3.unknown
        solver.set("timeout", max(1, int(left_s * 1000)))
    verdict = solver.check(*assumptions)
    if verdict == z3.unknown and _cancelled(solver.reason_unknown()):
        if limit_s is None or limit_s - (time.perf_counter() - started) > CANCEL_MARGIN_S:
            raise KeyboardInterrupt("z3: check interrupted")
    return verdict


CANCELLED = ("cancel", "interrupt")  # what Z3 says of a cancelled check ("canceled" of a time-out too)


def _cancelled(reason: str) -> bool:
    """Whether Z3's words say a check, or a call, was cancelled or interrupted."""
    return any(word in reason.lower() for word in CANCELLED)


CANCEL_MARGIN_S = 0.05  # a check cancelled with more than this left of its limit was not stopped by the limit

SOLVERS = {Strategy.SHORTEST: shortest, Strategy.OPTIMAL: optimal}


def _solve(problem: Problem, strategy: Strategy, limits: Limits) -> SearchResult:
    """shortest: incremental bounds; optimal: lexicographic tightening. sensible is left to the search engines.
    Z3 refusing a call because the context was interrupted (an interrupt that lands between checks) is an interrupt
    too, never an engine failure."""
    try:
        return SOLVERS[strategy](problem, limits)
    except z3.Z3Exception as err:
        if _cancelled(str(err)):
            raise KeyboardInterrupt("z3: interrupted") from None
        raise


Z3 = register(Engine("z3", tuple(SOLVERS), _solve,
                     "Z3 bounded model checking: shortest lengths, optimal plans, proofs within the horizon"))
