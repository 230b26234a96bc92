"""Render the Promela model of one (model, goal) from spec/: every number and rule comes from there.

One decision step is one ``d_step``, so Spin's search order and depth are the
interpreter's. The Promela state is the interpreter's state: ``lane``, ``lc`` (lane
changes), ``steps``, and both lanes' cells (slots past a lane's vehicle count stay 0, and
the scenario's counts are constants, so equal interpreter states are equal Promela
states). A ``crashed`` state has no successors: the path is abandoned. Reaching the goal
violates an assertion, whose trail is the plan; a ``printf`` per step carries the action
and the resulting cells for the replay.

Two ways to set the scenario: ``literal`` writes it into the model (a file a person can
run with Spin by hand); ``injected`` reads it when the verifier starts, from the
environment variable ``OVERTAKE_SCENARIO``, so that one compiled verifier serves every
scenario (and re-reads it on replay with ``pan -r``).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from spec.actions import ACTION_ORDER, ACTION_RULES, Action
from spec.constants import MAX_HORIZON
from spec.grid import PAPER_GRID, Grid
from spec.lanes import Lane
from spec.models import GOAL_RULES, MODEL_RULES, GoalKind, GoalRule, ModelKind, ModelRules
from spec.rules import behind_line, collision_span, left_path, nearest_span, passed_line
from spec.scenario import Problem, Scenario
from spec.sound import scenario_vehicles, sensed_extents

ENV_VAR = "OVERTAKE_SCENARIO"
LANE_CODE = {Lane.LEFT: 0, Lane.RIGHT: 1}


@dataclass(frozen=True, slots=True)
class Shape:
    """What a compiled verifier is specialised for: the model's rules, its goal, the grid (array sizes too)."""

    rules: ModelRules
    goal: GoalRule
    grid: Grid = PAPER_GRID
    capacity: int | None = None  # vehicles per lane the arrays hold; None: every scenario the grid accepts

    @property
    def model(self) -> ModelKind:
        return self.rules.kind

    @property
    def name(self) -> str:
        """``model-goal``, the cell length when it is not the paper's, the capacity when set: file and cache names."""
        cell = "" if self.grid.is_paper else f"-{float(self.grid.cell_m):g}m"
        room = "" if self.capacity is None else f"-v{self.capacity}"
        return f"{self.rules.kind.value}-{self.goal.kind.value}{cell}{room}"

    @property
    def max_vehicles(self) -> int:
        """Array sizes of the injected verifier."""
        return self.grid.road_cells + 1 if self.capacity is None else self.capacity


def standard_shape(model: ModelKind, goal: GoalKind, grid: Grid = PAPER_GRID) -> Shape:
    """The shape of one of the spec's models and goals."""
    return Shape(MODEL_RULES[model], GOAL_RULES[goal], grid)


#: Array sizes a verifier is built for, smallest first: pan hashes and compresses the whole state vector on every
#: state, and arrays sized for a full road (51 vehicles a lane on the paper's grid) make it eight times longer than
#: the few vehicles of a typical scenario need.
CAPACITIES = (2, 6)


def shape_of(problem: Problem) -> Shape:
    """The verifier shape that serves ``problem``: the smallest capacity that holds both of its lanes."""
    scenario = problem.scenario
    most = max(len(scenario.left_lane), len(scenario.right_lane))
    capacity = next((c for c in CAPACITIES if c >= most), None)
    return Shape(problem.rules, problem.goal, problem.grid, capacity)


def _cell(grid: Grid, cell: int) -> str:
    """A cell written relative to the AV's, as the template writes them: AV_CELL, AV_CELL + 1, AV_CELL - 1."""
    offset = cell - grid.av_cell
    return "AV_CELL" if offset == 0 else f"AV_CELL {'+' if offset > 0 else '-'} {abs(offset)}"


def _danger(shape: Shape) -> int:
    """The oncoming collision span as the template's symmetric DANGER around AV_CELL."""
    lo, hi = collision_span(Lane.RIGHT, shape.rules, shape.grid)
    av = shape.grid.av_cell
    if av - lo != hi - av:
        raise ValueError(f"promela: the oncoming collision span {lo}..{hi} is not symmetric around the AV's cell")
    return hi - av


def _left_hit(shape: Shape) -> str:
    """The left-lane collision span as a condition on ``left[i]``."""
    lo, hi = collision_span(Lane.LEFT, shape.rules, shape.grid)
    if lo == hi:
        return f"left[i] == {_cell(shape.grid, lo)}"
    return f"(left[i] >= {_cell(shape.grid, lo)} && left[i] <= {_cell(shape.grid, hi)})"


class Probe(enum.IntEnum):
    """What a sound model's verifier is asked (``Query.probe``): the plan search, or one sequence of actions known
    whole (the commitment semantics' proofs, ``spec.commitment.Proofs``): safe at every instant and safe for ever at
    its end (``ESCAPE``), and the goal there too (``WHOLE``); the start safe (``START``); the display states along it
    (``WALK``: its steps' checks only)."""

    SEARCH = 0
    ESCAPE = 1
    WHOLE = 2
    START = 3
    WALK = 4
    BATCH = 5  # several sequences, each ``ESCAPE`` or ``WHOLE``, one path each: those held are printed


@dataclass(frozen=True, slots=True)
class Query:
    """What a verifier is asked beyond its scenario. The paper model's: plans whose first action is one of ``firsts``
    (None: any), at least one action long when ``firsts`` is given (the commitment semantics' prediction). The sound
    model's: ``probe`` along ``sequence``; ``BATCH``: each of ``batch`` (its kind and its sequence)."""

    firsts: tuple[Action, ...] | None = None
    probe: Probe = Probe.SEARCH
    sequence: tuple[Action, ...] = ()
    batch: tuple[tuple[Probe, tuple[Action, ...]], ...] = ()


SEARCH = Query()
#: Every first action allowed (the paper model's ``firsts`` when a query names none).
ALL_FIRSTS = (1 << len(ACTION_ORDER)) - 1


def scenario_values(problem: Problem, query: Query = SEARCH) -> str:
    """The scenario as the injected verifier reads it: lane nl cells... nr cells... nt ft horizon; under the paper's
    rules then the first actions allowed (a bitmask in ``ACTION_ORDER``) and whether a plan must have an action;
    under the sound model then each phantom's edge (``spec.sound.Sound.phantoms``: where its sensor's view ended),
    and 0, or 1 and each vehicle's sensed interval (``spec.sound.sensed_extents``, same-direction then oncoming, lo hi
    each, as Python's ``repr`` writes a double: ``strtod`` reads it back exactly), the measured speeds, then the
    probe: 0, its code (the start), or its code, the sequence's length and its action codes (a batch: how many, then
    each one's kind, length and codes)."""
    s = problem.scenario
    first_target = s.target_indices[0] if s.target_indices else 0
    words: list[object] = [LANE_CODE[s.lane], len(s.left_lane), *s.left_lane, len(s.right_lane), *s.right_lane,
                           len(s.target_indices), first_target, problem.horizon]
    if s.sound is None:
        if query.firsts is None:
            return " ".join(map(str, [*words, ALL_FIRSTS, 0]))
        return " ".join(map(str, [*words, sum(1 << ACTION_ORDER.index(a) for a in query.firsts), 1]))
    words += [repr(float(p.dx_m)) for p in s.sound.phantoms()]
    if s.left_m is None and s.right_m is None:
        words.append(0)
    else:
        same, oncoming = sensed_extents(s.lane, s.left_lane, s.right_lane, s.grid, s.left_m, s.right_m)
        words += [1, *(repr(float(x)) for pair in (*same, *oncoming) for x in pair)]
    words += _measured_speeds(s)
    words.append(int(query.probe))
    if query.probe is Probe.BATCH:
        words.append(len(query.batch))
        for kind, sequence in query.batch:
            words += [int(kind), len(sequence), *(ACTION_ORDER.index(a) for a in sequence)]
    elif query.probe not in (Probe.SEARCH, Probe.START):
        words += [len(query.sequence), *(ACTION_ORDER.index(a) for a in query.sequence)]
    return " ".join(map(str, words))


def _measured_speeds(s: Scenario) -> list[object]:
    """0, or 1 and for each sensed vehicle (same-direction then oncoming) 0, or 1 and where it can be at the plan's
    start and how it may move from there (``spec.sound.vehicles``: its interval widened by its own error, its speed
    interval aged by the snapshot's age, its top): lo hi low high top."""
    if s.sound is None or (s.left_mps is None and s.right_mps is None):
        return [0]
    words: list[object] = [1]
    for v in scenario_vehicles(s):
        if v.index is None:
            continue  # a phantom: the verifier places it from its edge
        if v.dynamics is None:
            words.append(0)
            continue
        low, high = v.dynamics.speed_mps
        words += [1, *(repr(float(x)) for x in (v.lo_m, v.hi_m, low, high, v.dynamics.top_mps))]
    return words


def render(shape: Shape, scenario: Scenario | None = None, horizon: int | None = None) -> str:
    """The Promela model: literal when ``scenario`` is given, else injected at run time."""
    rules, goal, grid = shape.rules, shape.goal, shape.grid
    max_left = max(1, len(scenario.left_lane)) if scenario else shape.max_vehicles
    max_right = max(1, len(scenario.right_lane)) if scenario else shape.max_vehicles
    what = f"{rules.kind.value} model, goal {goal.kind.value}" + ("" if grid.is_paper else f", {grid.describe()}")
    parts = [
        f"/* overtake-mc: {what}; rendered from spec/, do not edit */",
        f"#define AV_CELL {grid.av_cell}",
        f"#define DANGER {_danger(shape)}",
        f"#define MAX_LC {rules.max_lane_changes}",
        f"#define MAXL {max_left}",
        f"#define MAXR {max_right}",
        "#define LEFT 0",
        "#define RIGHT 1",
        "",
        "short left[MAXL];   /* left-lane vehicles, ascending */",
        "short right[MAXR];  /* oncoming vehicles, ascending */",
        "byte nl; byte nr; byte nt; byte ft; byte horizon;  /* the scenario: constant after start */",
        "bit lane; byte lc; byte steps; bool crashed; bool reached;",
        "byte firsts;  /* the first actions allowed (bit per action) */",
        "bit least;  /* the commitment semantics' prediction: one action at least, the start unchecked (the sound "
        "model checked it) */",
        "byte i;  /* scratch index, reset to 0 at the end of every atomic step, so it is constant */",
        "",
        _INLINES.replace("LEFT_HIT", _left_hit(shape)),
        _goal_inline(goal, grid),
        "active proctype av() {",
        _load_literal(scenario, horizon) if scenario else _load_injected(),
        "  d_step { if :: !least -> collide() :: else -> skip fi;",
        "           if :: !crashed -> printf(\"INIT \"); print_state(); goal_check(); reached = reached && !least "
        ":: else -> skip fi;",
        "           assert(!reached); i = 0 }",
        "  do",
        *(_option(action, grid) for action in ACTION_ORDER),
        "  od",
        "}",
    ]
    return "\n".join(parts) + "\n"


_INLINES = """inline collide() {
  if
  :: lane == LEFT ->
     i = 0; do :: i < nl -> crashed = crashed || LEFT_HIT; i++ :: else -> break od
  :: else ->
     i = 0; do :: i < nr -> crashed = crashed || (right[i] >= AV_CELL - DANGER && right[i] <= AV_CELL + DANGER); i++
               :: else -> break od
  fi
}
inline shift_left(d) { i = 0; do :: i < nl -> left[i] = left[i] + d; i++ :: else -> break od }
inline tick() { i = 0; do :: i < nr -> right[i] = right[i] - 1; i++ :: else -> break od; collide() }
inline print_state() {
  printf("%d %d %d |", lane, lc, steps);
  i = 0; do :: i < nl -> printf(" %d", left[i]); i++ :: else -> break od; printf(" |");
  i = 0; do :: i < nr -> printf(" %d", right[i]); i++ :: else -> break od; printf("\\n")
}"""


def _goal_inline(goal: GoalRule, grid: Grid) -> str:
    """The goal as a conjunction, field by field from the GoalRule, each line from its rule in ``spec.rules``."""
    lines = ["inline goal_check() {", "  reached = 1;"]
    if goal.av_lane is not None:
        lines.append(f"  reached = reached && lane == {goal.av_lane.name};")
    if goal.targets_behind:
        below = _cell(grid, behind_line(grid) + 1)
        lines.append(f"  i = ft; do :: i < ft + nt -> reached = reached && left[i] < {below}; i++ :: else -> break od;")
    span = nearest_span(goal, grid)
    if span is not None:
        lo, hi = span
        within = (f"left[ft] == {_cell(grid, lo)}" if lo == hi
                  else f"left[ft] >= {_cell(grid, lo)} && left[ft] <= {_cell(grid, hi)}")
        lines.append(f"  reached = reached && nt > 0 && {within};")
    if goal.oncoming_passed:
        passed = _cell(grid, passed_line(grid))
        lines.append(f"  i = 0; do :: i < nr -> reached = reached && right[i] <= {passed}; i++ :: else -> break od;")
    lines.append("}")
    return "\n".join(lines)


def _option(action: Action, grid: Grid) -> str:
    """One decision step as one atomic transition: guard, effect, check, ticks, goal."""
    rule = ACTION_RULES[action]
    guard = ["!crashed", "steps < horizon", f"(steps > 0 || ((firsts >> {ACTION_ORDER.index(action)}) & 1))"]
    body = []
    if rule.from_lane is not None:
        guard.append(f"lane == {rule.from_lane.name}")
    if rule.changes_lane:
        guard.append("lc < MAX_LC")
        body += [f"lane = {rule.to_lane.name if rule.to_lane else 'lane'}", "lc++"]
    shift = grid.left_shift(action)
    path = list(left_path(shift)) if shift else []  # one cell at a time, a collision check after each
    for k, moved in enumerate(path):
        body.append(f"shift_left({moved - (path[k - 1] if k else 0)})")
        if k < len(path) - 1:
            body.append("collide()")
    body += ["steps++", "collide()"]
    body += ["tick()"] * grid.ticks(action)
    finish = (f'if :: !crashed -> printf("STEP {action.value} "); print_state(); goal_check(); assert(!reached)'
              " :: else -> skip fi; i = 0")
    return f"  :: d_step {{ {' && '.join(guard)} ->\n       {'; '.join(body)};\n       {finish} }}"


def _load_literal(scenario: Scenario, horizon: int | None) -> str:
    values = [f"lane = {LANE_CODE[scenario.lane]}", f"nl = {len(scenario.left_lane)}",
              f"nr = {len(scenario.right_lane)}", f"nt = {len(scenario.target_indices)}",
              f"ft = {scenario.target_indices[0] if scenario.target_indices else 0}",
              f"horizon = {scenario.horizon if horizon is None else horizon}", f"firsts = {ALL_FIRSTS}", "least = 0"]
    values += [f"left[{i}] = {c}" for i, c in enumerate(scenario.left_lane)]
    values += [f"right[{i}] = {c}" for i, c in enumerate(scenario.right_lane)]
    return "  d_step { " + "; ".join(values) + " }"


def _load_injected() -> str:
    return f"""  c_code {{
    char *text = getenv("{ENV_VAR}"); char *end; long v[2 * MAXL + 10]; int n = 0, j, at;
    if (!text) {{ fprintf(stderr, "overtake: {ENV_VAR} is not set\\n"); exit(2); }}
    while (n < 2 * MAXL + 10) {{ v[n] = strtol(text, &end, 10); if (end == text) break; n++; text = end; }}
    at = 0; now.lane = v[at++]; now.nl = v[at++];
    for (j = 0; j < now.nl; j++) now.left[j] = v[at++];
    now.nr = v[at++];
    for (j = 0; j < now.nr; j++) now.right[j] = v[at++];
    now.nt = v[at++]; now.ft = v[at++]; now.horizon = v[at++];
    if (at + 2 != n || v[at] < 0 || v[at] > {ALL_FIRSTS} || v[at + 1] < 0 || v[at + 1] > 1) {{
      fprintf(stderr, "overtake: malformed {ENV_VAR} (the first actions allowed)\\n"); exit(2); }}
    now.firsts = v[at++]; now.least = v[at++];
    if (at != n || now.nl > MAXL || now.nr > MAXR || now.horizon > {MAX_HORIZON}) {{
      fprintf(stderr, "overtake: malformed {ENV_VAR}\\n"); exit(2); }}
  }};"""


def render_for(problem: Problem) -> str:
    """The literal model of one problem: what ``overtake promela`` writes."""
    return render(shape_of(problem), problem.scenario, problem.horizon)
