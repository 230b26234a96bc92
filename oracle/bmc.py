"""The Z3 bounded encoding: k decision steps unrolled from spec/, solved incrementally.

State per step: ``right`` (the AV's lane), ``lc`` (lane changes), ``l`` (left-lane
offset: every left-lane vehicle sits at its initial cell + l) and ``o`` (oncoming ticks:
every oncoming vehicle sits at its initial cell - o). All left-lane vehicles move
together and so do all oncoming ones, so these four values are the whole state; each
vehicle's collision and goal conditions are written on its own cell. Every intermediate
oncoming tick gets its own collision check, as in the interpreter.

The vehicles' initial cells are parameters of the encoding, not constants: an encoding
depends only on the problem's *shape* (the AV's lane, how many vehicles each lane holds,
which are targets, the model, the goal, the horizon, the grid). A process keeps one solver
per shape and strategy, and each problem fixes its cells by assumption literals, so what the
solver learned on one problem (lemmas over the parameters, valid for every problem of that
shape) carries over to the next: a campaign of thousands of similar scenarios pays for
building an unrolling once per shape, the way the Spin engine serves many scenarios from
one verifier process. Least costs, lengths and statuses do not depend on what the solver
saw before; which of several equally good plans it returns may (``isolated()`` gives a
solver of its own to each problem, for reproducers).

One decision step is built once, as a template over placeholder states, and every step of the
unrolling is that template with the step's own variables substituted in (one call into Z3, not
thousands of Python-built terms).

``shortest`` adds one step at a time and asks, under assumptions, whether the goal holds at
step k (having not held before): the first satisfiable k is the shortest length; all bounds
unsatisfiable up to the horizon is a proof of "no plan within the horizon". ``optimal``
unrolls to the horizon with a symbolic length and minimises the lexicographic cost term by
term. A solver time-out is "incomplete", never "no plan".
"""

from __future__ import annotations

import time
from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TypeVar

import z3

from spec.actions import ACTION_ORDER, ACTION_RULES, Action
from spec.answers import Limits, SearchResult, Status, Strategy
from spec.cost import COST_DOC, COST_TERMS, total_cost
from spec.lanes import Lane
from spec.rules import behind_line, collision_span, left_path, nearest_span, passed_line
from spec.scenario import Problem, Scenario
from spec.state import State


@dataclass(frozen=True, slots=True)
class Step:
    """The Z3 variables of one state."""

    right: z3.BoolRef
    lc: z3.ArithRef
    l: z3.ArithRef  # noqa: E741  (the left-lane offset, named as in SPEC.md)
    o: z3.ArithRef


class Encoding:
    """The transition system of one problem shape as Z3 terms over its vehicles' cells (``left``, ``right``: one
    integer parameter per vehicle); ``present`` guards each vehicle (explanations)."""

    def __init__(self, problem: Problem, present: dict[tuple[Lane, int], z3.BoolRef] | None = None) -> None:
        self.problem = problem
        scenario = problem.scenario
        self.present = present or {}
        self.left = tuple(z3.Int(f"left_cell_{i}") for i in range(len(scenario.left_lane)))
        self.right = tuple(z3.Int(f"right_cell_{i}") for i in range(len(scenario.right_lane)))
        self.steps: list[Step] = []
        self.actions: list[z3.ArithRef] = []
        self.targets = list(scenario.target_indices)
        self.grid = problem.grid
        self.ticks = {a: self.grid.ticks(a) for a in ACTION_ORDER}
        start = self.new_step()
        #: the start's place; its safety holds where ``start_checked`` is assumed (every answer but the commitment
        #: semantics' prediction, whose start the sound model checks: ``spec.commitment``)
        self.start_checked = z3.Bool("start_checked")
        self.initial = z3.And(start.right == (scenario.lane is Lane.RIGHT), start.lc == 0, start.l == 0, start.o == 0,
                              z3.Implies(self.start_checked, self.safe(start.right, start.l, 0, start.o, 0)))
        here, after, action = _placeholder("a"), _placeholder("b"), z3.Int("action")
        self._step_template = (here, action, after, self.transition(here, action, after))
        self._goal_template = (here, self.goal(here))

    def cells(self, scenario: Scenario) -> list[tuple[z3.ArithRef, int]]:
        """Each cell parameter with its value in ``scenario`` (a scenario of this encoding's shape)."""
        return [*zip(self.left, scenario.left_lane, strict=True), *zip(self.right, scenario.right_lane, strict=True)]

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
        each of ``ticks`` oncoming ticks from ``o_start``: per vehicle, on its own cell."""
        rules = self.problem.rules
        (l_lo, l_hi), (r_lo, r_hi) = (collision_span(lane, rules, self.grid) for lane in (Lane.LEFT, Lane.RIGHT))
        passed = [(i, c - shift + j) for i, c in enumerate(self.left) for j in left_path(shift)]
        left_ok = [z3.Implies(self._here(Lane.LEFT, i), z3.Or(cell + l_end < l_lo, cell + l_end > l_hi))
                   for i, cell in passed]
        right_ok = [z3.Implies(self._here(Lane.RIGHT, i), z3.Or(c - (o_start + j) > r_hi, c - (o_start + j) < r_lo))
                    for i, c in enumerate(self.right) for j in range(ticks + 1)]
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

    def _effect(self, action: Action) -> tuple[int, int]:
        """What a step's collision condition depends on: how far it shifts the left lane, and its ticks."""
        return self.grid.left_shift(action), self.ticks[action]

    def goal(self, s: Step) -> z3.BoolRef:
        """The problem's goal on the state ``s``, field by field from the GoalRule."""
        goal, parts = self.problem.goal, []
        if goal.av_lane is not None:
            parts.append(s.right == (goal.av_lane is Lane.RIGHT))
        cells, grid = self.left, self.grid
        if goal.targets_behind:
            parts += [z3.Implies(self._here(Lane.LEFT, i), cells[i] + s.l <= behind_line(grid)) for i in self.targets]
        span = nearest_span(goal, grid)
        if span is not None:
            parts.append(self._nearest_within(s, span))
        if goal.oncoming_passed:
            parts += [z3.Implies(self._here(Lane.RIGHT, i), c - s.o <= passed_line(grid))
                      for i, c in enumerate(self.right)]
        return z3.And(*parts, True)

    def _nearest_within(self, s: Step, span: tuple[int, int]) -> z3.BoolRef | bool:
        """The nearest present target is within ``span``; false without one."""
        result: z3.BoolRef | bool = False
        for i in reversed(self.targets):
            here, cell = self._here(Lane.LEFT, i), self.left[i] + s.l
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
        """The plan of ``length`` actions in ``model`` and the states the model itself assigns along it, cells
        included (the pipeline and the trace-equality property compare them with the interpreter's)."""
        def value(term: z3.ArithRef) -> int:
            return int(model.eval(term, model_completion=True).as_long())

        actions = tuple(ACTION_ORDER[value(a)] for a in self.actions[:length])
        return actions, tuple(self._state(model, value, k) for k in range(length + 1))

    def _state(self, model: z3.ModelRef, value: Callable[[z3.ArithRef], int], k: int) -> State:
        s = self.steps[k]
        right = z3.is_true(model.eval(s.right, model_completion=True))
        return State(Lane.RIGHT if right else Lane.LEFT, tuple(value(c + s.l) for c in self.left),
                     tuple(value(c - s.o) for c in self.right), value(s.lc), k)


def shape(problem: Problem) -> Hashable:
    """What an encoding depends on: everything in ``problem`` but the vehicles' cells."""
    scenario = problem.scenario
    return (scenario.lane, len(scenario.left_lane), len(scenario.right_lane), scenario.target_indices,
            problem.rules, problem.goal, problem.horizon, problem.grid)


def _placeholder(name: str) -> Step:
    """The variables of a template state."""
    return Step(z3.Bool(f"{name}_right"), z3.Int(f"{name}_lc"), z3.Int(f"{name}_l"), z3.Int(f"{name}_o"))


def _pairs(template: Step, step: Step) -> list[tuple[z3.ExprRef, z3.ExprRef]]:
    return [(template.right, step.right), (template.lc, step.lc), (template.l, step.l), (template.o, step.o)]


class Kept:
    """One shape's encoding on one solver, kept for every problem of that shape; conditions a problem assumes
    (its cells, a cost bound) are literals defined once, so assuming them leaves no trace."""

    def __init__(self, problem: Problem) -> None:
        self.enc = Encoding(problem)
        self.solver = z3.SolverFor("QF_LIA")
        self.gave_up = False  # a check ran out of time or was cancelled: the solver is not kept
        self.model: z3.ModelRef | None = None  # the last satisfiable check's model, checked (``check``)
        self._literals: dict[int, tuple[z3.BoolRef, z3.BoolRef]] = {}
        self._asserted: list[z3.BoolRef] = []
        self._whole: z3.BoolRef | None = None  # the conjunction of _asserted, made when a model is checked

    def add(self, *constraints: z3.BoolRef) -> None:
        self.solver.add(*constraints)
        self._asserted += constraints
        self._whole = None

    def check(self, limits: Limits | None, started: float, *assumptions: z3.BoolRef) -> z3.CheckSatResult:
        """One check within what is left of the time limit (``_check``); on "sat", ``self.model`` is its model,
        trusted only if it satisfies everything asserted and assumed: Z3 interrupted while it took in constraints
        (Ctrl-C between checks) answers "sat" with a model of part of them, and interrupted just after a check it
        has no model to give ("there is no current model"). Either is an interrupt, never an answer."""
        self.model = None
        verdict = _check(self.solver, limits, started, *assumptions)  # an exception drops the solver (_solver_for)
        if verdict == z3.unknown:
            self.gave_up = True
        elif verdict == z3.sat:
            if self._whole is None:
                self._whole = z3.And(*self._asserted)
            try:
                model = self.solver.model()
                whole = all(z3.is_true(model.eval(c)) for c in (self._whole, *assumptions))
            except z3.Z3Exception as err:
                raise KeyboardInterrupt(f"z3: interrupted after a check ({err})") from None
            if not whole:
                raise KeyboardInterrupt("z3: interrupted (a model of part of the constraints)")
            self.model = model
        return verdict

    def checked_model(self) -> z3.ModelRef:
        """The model of the last check, which was satisfiable."""
        if self.model is None:
            raise RuntimeError("z3: no model: the last check was not satisfiable")
        return self.model

    def literal(self, condition: z3.BoolRef) -> z3.BoolRef:
        """A literal that implies ``condition``, defined the first time it is asked for."""
        key = condition.get_id()  # Z3 terms are hash-consed: an equal condition is the same term, while it lives
        if key not in self._literals:
            self._literals[key] = (condition, z3.Bool(f"assume_{len(self._literals)}"))  # kept alive with its id
            self.add(z3.Implies(self._literals[key][1], condition))
        return self._literals[key][1]

    def fixing(self, scenario: Scenario) -> list[z3.BoolRef]:
        """The literals that fix every cell parameter at ``scenario``'s cells."""
        return [self.literal(term == value) for term, value in self.enc.cells(scenario)]


class Shortest(Kept):
    """``shortest``'s solver: the unrolling grows one step at a time, as the longest problem so far needed;
    ``reached[k]`` is a literal equal to the goal after k actions."""

    def __init__(self, problem: Problem) -> None:
        super().__init__(problem)
        self.add(self.enc.initial)
        self.reached: list[z3.BoolRef] = []
        self.last_bound: int | None = None  # the first satisfiable bound of the last problem (horizon + 1: none)

    def goal_before(self, k: int) -> z3.BoolRef:
        """A literal that implies the goal holds after fewer than k actions."""
        self.goal(k - 1)
        return self.literal(z3.Or(*self.reached[:k]))

    def goal(self, k: int) -> z3.BoolRef:
        while len(self.reached) <= k:
            if self.reached:
                self.add(self.enc.extend(), self.enc.bounds(len(self.reached)))
            literal = z3.Bool(f"goal_{len(self.reached)}")
            self.add(literal == self.enc.goal_at(len(self.reached)))
            self.reached.append(literal)
        return self.reached[k]


class Optimal(Kept):
    """``optimal``'s solver: the whole unrolling to the horizon with a symbolic length, and the cost terms."""

    def __init__(self, problem: Problem) -> None:
        super().__init__(problem)
        self.length, constraints, self.terms, self.counted = bounded(self.enc)
        self.add(*constraints)
        self.last_cost: tuple[int, ...] | None = None  # the least cost of the last problem solved here

    def costing(self, cost: tuple[int, ...]) -> list[z3.BoolRef]:
        """The literals that fix every cost term at ``cost`` (COST_TERMS order)."""
        return [self.equal(name, value) for name, value in zip(COST_TERMS, cost, strict=True)]

    def below(self, name: str, value: int) -> z3.BoolRef:
        """A literal that implies the term is below ``value``: a cardinality constraint on a term that counts steps
        (Z3 propagates those as a count, where a sum of 0/1 terms takes case splits: 1.34x faster on 600 problems
        of a sweep)."""
        literals = self.counted.get(name)
        if not literals:
            return self.literal(self.terms[name] < value)
        return self.literal(z3.AtMost(*literals, value - 1) if value > 0 else z3.BoolVal(False))

    def equal(self, name: str, value: int) -> z3.BoolRef:
        literals = self.counted.get(name)
        if not literals:
            return self.literal(self.terms[name] == value)
        return self.literal(z3.And(z3.AtMost(*literals, value), z3.AtLeast(*literals, value)))


KEEP_AT_MOST = 256  # shapes kept per process (least recently used dropped): a campaign meets tens to hundreds
_kept: OrderedDict[tuple[type[Kept], Hashable], Kept] = OrderedDict()
K = TypeVar("K", bound=Kept)
_isolated = False


@contextmanager
def isolated() -> Iterator[None]:
    """Within this block every problem gets a solver of its own, as in a fresh process: its plan does not depend
    on what was solved before (reproducers need that; costs and statuses never depend on it)."""
    global _isolated
    before, _isolated = _isolated, True
    try:
        yield
    finally:
        _isolated = before


@dataclass(frozen=True, slots=True)
class Expected:
    """What another engine answered on one problem (a cross-check's reference): its shortest plan's length, the
    least cost. Z3 guesses them first, as it guesses its last problem's answers: a guess orders the checks, never
    decides the answer (each is proved the same way, and a wrong one costs a check)."""

    length: int | None = None
    cost: tuple[int, ...] | None = None


_expected: dict[Problem, Expected] = {}


@contextmanager
def expecting(expected: Mapping[Problem, Expected]) -> Iterator[None]:
    """Within this block Z3's ``shortest`` and ``optimal`` (paper model and sound model) start on ``expected``'s
    answers for its problems instead of the last problem's."""
    _expected.update(expected)
    try:
        yield
    finally:
        for problem in expected:
            _expected.pop(problem, None)


def expected_length(problem: Problem, last: int | None) -> int | None:
    """The bound a warm start guesses first: the length expected on ``problem``, or the last problem's bound."""
    found = _expected.get(problem)
    return last if found is None or found.length is None else found.length


def expected_cost(problem: Problem, last: tuple[int, ...] | None) -> tuple[int, ...] | None:
    """The cost a warm start guesses first: the one expected on ``problem``, or the last problem's least cost."""
    found = _expected.get(problem)
    return last if found is None or found.cost is None else found.cost


@contextmanager
def _solver_for(kind: type[K], problem: Problem) -> Iterator[K]:
    """The kept solver of ``problem``'s shape (made if new). One that gave up, was interrupted or raised is
    dropped: what a cancelled check leaves behind is not trusted."""
    key = (kind, shape(problem))
    found = None if _isolated else _kept.pop(key, None)
    kept = found if isinstance(found, kind) else kind(problem)
    yield kept  # an exception leaves it out of _kept
    if not (_isolated or kept.gave_up):
        _kept[key] = kept
        while len(_kept) > KEEP_AT_MOST:
            _kept.popitem(last=False)


def _first_in(action_var: z3.ArithRef, firsts: Sequence[Action]) -> z3.BoolRef:
    """The action numbered ``action_var`` is one of ``firsts``."""
    return z3.Or(*[action_var == ACTION_ORDER.index(a) for a in firsts]) if firsts else z3.BoolVal(False)


def shortest(problem: Problem, limits: Limits | None = None, firsts: Sequence[Action] | None = None) -> SearchResult:
    """The smallest k whose bound is satisfiable, incrementally, or a proof that none is up to the horizon. With
    ``firsts`` (the commitment semantics' prediction, ``spec.commitment``): at least one action, the first one of
    ``firsts``, from a start whose collisions are not checked (the sound model checked it); no warm start.

    Warm start: a kept solver remembers the last problem's first satisfiable bound g (in a campaign,
    often this one's too) and first asks whether the goal holds anywhere below it, one check for
    bounds 0 .. g - 1 together: "unsat" proves them all at once and the bounds go on from g; "sat"
    (the guess was too high) goes back to bound 0. The answer is proved the same way either way."""
    started = time.perf_counter()
    horizon = problem.horizon
    with _solver_for(Shortest, problem) as kept:
        fixed, not_before, start = kept.fixing(problem.scenario), list[z3.BoolRef](), 0
        fixed += [kept.enc.start_checked] if firsts is None else []
        if firsts is not None:
            kept.goal(1)
            fixed.append(kept.literal(_first_in(kept.enc.actions[0], firsts)))
            start = 1
        last = expected_length(problem, kept.last_bound)
        guess = None if last is None or firsts is not None else min(last, horizon + 1)
        if guess is not None and guess > 1:
            verdict = kept.check(limits, started, *fixed, kept.goal_before(guess))
            if verdict == z3.unknown:
                return SearchResult(Status.INCOMPLETE, (), 0, f"z3: {kept.solver.reason_unknown()} below bound {guess}")
            if verdict == z3.unsat:
                start, not_before = guess, [z3.Not(kept.goal(k)) for k in range(guess)]
        for k in range(start, horizon + 1):
            reached = kept.goal(k)
            verdict = kept.check(limits, started, *fixed, *not_before, reached)
            if verdict == z3.sat:
                kept.last_bound = k if firsts is None else kept.last_bound
                actions, states = kept.enc.decode(kept.checked_model(), k)
                return SearchResult(Status.PLAN, actions, k + 1, f"shortest: bound {k} satisfiable", states)
            if verdict == z3.unknown:
                return SearchResult(Status.INCOMPLETE, (), k, f"z3: {kept.solver.reason_unknown()} at bound {k}")
            not_before.append(z3.Not(reached))
        kept.last_bound = horizon + 1 if firsts is None else kept.last_bound
    return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), horizon + 1,
                        f"proved: every bound up to {horizon} is unsatisfiable")


def bounded(enc: Encoding) -> tuple[z3.ArithRef, list[z3.BoolRef], dict[str, z3.ArithRef], dict[str, list[z3.BoolRef]]]:
    """Plans of any length up to the horizon: a symbolic length N; steps after N repeat the last state. Also the
    plan's cost, term by term (COST_TERMS), and for the terms that count steps (right-lane steps, brakes) one
    literal per step that is true iff the step counts.

    Everything one step adds (its transition or, from N on, a copy of its state; the goal at N and not before;
    whether it counts for each term) is one template over placeholder states, the step's number and N, substituted
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
    counts = {"right_lane_steps": z3.And(live, after.right), "brakes": z3.And(live, action == brake)}
    constraints = [enc.initial, length >= 0, length <= horizon]
    counted: dict[str, list[z3.BoolRef]] = {name: [] for name in counts}
    for k in range(horizon):
        a, action_var, b = enc.advance()
        pairs = [(k_var, z3.IntVal(k)), (action, action_var), *_pairs(here, a), *_pairs(after, b)]
        constraints.append(z3.substitute(move, *pairs))
        for name, condition in counts.items():
            literal = z3.Bool(f"{name}_{k + 1}")
            constraints.append(literal == z3.substitute(condition, *pairs))
            counted[name].append(literal)
    constraints.append(z3.substitute(reached, (k_var, z3.IntVal(horizon)), *_pairs(here, enc.steps[horizon])))
    terms = {"lane_changes": enc.steps[-1].lc, "length": length,
             **{name: z3.Sum([z3.If(x, 1, 0) for x in literals]) if literals else z3.IntVal(0)
                for name, literals in counted.items()}}
    return length, constraints, terms, counted


def optimal(problem: Problem, limits: Limits | None = None, firsts: Sequence[Action] | None = None) -> SearchResult:
    """The plan of least cost (COST_DOC) among all plans of at most ``horizon`` actions (with ``firsts``, as
    ``shortest``'s: at least one action, the first one of ``firsts``).

    Lexicographic, term by term in COST_TERMS order, by bisection: any plan first; then for each
    term, between a floor (0, then one above the last unsatisfiable bound) and the best value a
    model has shown, ask for a plan whose term is at most a midpoint (an assumption, so an
    unsatisfiable bound leaves no trace): a model lowers the best to its own value, "unsat" raises
    the floor, until they meet; the term is fixed there (an assumption too). The last model is a
    least-cost plan.

    Warm start: a kept solver remembers the least cost of the last problem it solved, which in a
    campaign (scenarios one cell apart) is often this one's too. The first check asks for a plan of
    exactly that cost, and each term's bisection tries that value, then one below it, before
    halving. The guess orders the questions only: the answer is proved the same way (a model for
    the cost, "unsat" below it), and a wrong guess costs a check or two. On a campaign's kept
    solvers this asks 0.74x the checks of a cold bisection, which asks 0.86x the checks of
    tightening one below the best each time; ``z3.Optimize`` takes about twice as long."""
    started = time.perf_counter()
    with _solver_for(Optimal, problem) as kept:
        solver, terms, assumed = kept.solver, kept.terms, kept.fixing(problem.scenario)
        assumed += [kept.enc.start_checked] if firsts is None else []
        if firsts is not None:
            if problem.horizon < 1:
                return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), 0, "proved: no plan of at least one action "
                                    "within a horizon of 0")
            assumed.append(kept.literal(z3.And(kept.length >= 1, _first_in(kept.enc.actions[0], firsts))))
        guess, model, checks = expected_cost(problem, kept.last_cost), None, 0
        if guess is not None:
            verdict, checks = kept.check(limits, started, *assumed, *kept.costing(guess)), 1
            if verdict == z3.unknown:
                return _gave_up(solver, checks)
            model = kept.checked_model() if verdict == z3.sat else None
        if model is None:
            verdict, checks = kept.check(limits, started, *assumed), checks + 1
            if verdict == z3.unsat:
                return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), checks,
                                    f"proved: no plan of at most {problem.horizon} actions")
            if verdict == z3.unknown:
                return _gave_up(solver, checks)
            model = kept.checked_model()
        for index, name in enumerate(COST_TERMS):
            floor, best = 0, model.eval(terms[name], model_completion=True).as_long()
            tries = [] if guess is None else [guess[index], guess[index] - 1]  # the guess, then just below it
            while floor < best:
                middle = next((t for t in tries if floor <= t < best), (floor + best) // 2)
                tries = [t for t in tries if t != middle]
                verdict, checks = kept.check(limits, started, *assumed, kept.below(name, middle + 1)), checks + 1
                if verdict == z3.unknown:
                    return _gave_up(solver, checks)
                if verdict == z3.unsat:
                    floor = middle + 1
                else:
                    model = kept.checked_model()
                    best = model.eval(terms[name], model_completion=True).as_long()
            assumed.append(kept.equal(name, best))
        kept.last_cost = tuple(model.eval(terms[name], model_completion=True).as_long() for name in COST_TERMS)
        n = model.eval(kept.length).as_long()
        actions, states = kept.enc.decode(model, n)
    cost = dict(zip(COST_TERMS, total_cost(zip(actions, states[1:])), strict=True))  # as the model's states say
    return SearchResult(Status.PLAN, actions, checks, f"optimal under {COST_DOC}", states,
                        {"cost": cost, "cost_order": list(COST_TERMS)})


def _gave_up(solver: z3.Solver, checks: int) -> SearchResult:
    return SearchResult(Status.INCOMPLETE, (), checks, f"z3: {solver.reason_unknown()} after {checks} checks")


def _check(solver: z3.Solver, limits: Limits | None, started: float, *assumptions: z3.BoolRef) -> z3.CheckSatResult:
    """One check within what is left of the time limit. A check cancelled before its limit was interrupted (Ctrl-C,
    or a signal handler cancelling it): that is KeyboardInterrupt, never an "incomplete" answer."""
    limit_s = None if limits is None else limits.timeout_s
    timeout_ms = NO_TIMEOUT_MS  # set every time: a kept solver carries the last problem's limit otherwise
    if limit_s is not None:
        left_s = limit_s - (time.perf_counter() - started)
        if left_s <= 0:
            return z3.unknown
        timeout_ms = max(1, int(left_s * 1000))
    solver.set("timeout", timeout_ms)
    verdict = solver.check(*assumptions)
    if verdict == z3.unknown and _cancelled(solver.reason_unknown()):
        if limit_s is None or limit_s - (time.perf_counter() - started) > CANCEL_MARGIN_S:
            raise KeyboardInterrupt("z3: check interrupted")
    return verdict


NO_TIMEOUT_MS = 4294967295  # Z3's own default for "timeout": no limit

CANCELLED = ("cancel", "interrupt")  # what Z3 says of a cancelled check ("canceled" of a time-out too)


def _cancelled(reason: str) -> bool:
    """Whether Z3's words say a check, or a call, was cancelled or interrupted."""
    return any(word in reason.lower() for word in CANCELLED)


CANCEL_MARGIN_S = 0.05  # a check cancelled with more than this left of its limit was not stopped by the limit

SOLVERS = {Strategy.SHORTEST: shortest, Strategy.OPTIMAL: optimal}
