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

from dataclasses import dataclass

from spec.actions import ACTION_ORDER, ACTION_RULES, Action
from spec.constants import AV_CELL, MAX_HORIZON, ROAD_CELLS
from spec.lanes import Lane
from spec.models import GOAL_RULES, MODEL_RULES, GoalKind, ModelKind, goal_kind
from spec.scenario import Problem, Scenario

#: Array sizes of the injected verifier: every scenario the spec accepts fits.
MAX_VEHICLES = ROAD_CELLS + 1
ENV_VAR = "OVERTAKE_SCENARIO"
LANE_CODE = {Lane.LEFT: 0, Lane.RIGHT: 1}


@dataclass(frozen=True, slots=True)
class Shape:
    """What a compiled verifier is specialised for: the model, its goal, and the array sizes."""

    model: ModelKind
    goal: GoalKind
    max_left: int = MAX_VEHICLES
    max_right: int = MAX_VEHICLES


def shape_of(problem: Problem) -> Shape:
    """The verifier shape that serves ``problem``."""
    return Shape(problem.model, problem.goal.kind)


def scenario_values(problem: Problem) -> str:
    """The scenario as the injected verifier reads it: lane nl cells... nr cells... nt ft horizon."""
    s = problem.scenario
    first_target = s.target_indices[0] if s.target_indices else 0
    words = [LANE_CODE[s.lane], len(s.left_lane), *s.left_lane, len(s.right_lane), *s.right_lane,
             len(s.target_indices), first_target, problem.horizon]
    return " ".join(map(str, words))


def render(shape: Shape, scenario: Scenario | None = None, horizon: int | None = None) -> str:
    """The Promela model: literal when ``scenario`` is given, else injected at run time."""
    rules, goal = MODEL_RULES[shape.model], GOAL_RULES[shape.goal]
    max_left = max(1, len(scenario.left_lane)) if scenario else shape.max_left
    max_right = max(1, len(scenario.right_lane)) if scenario else shape.max_right
    parts = [
        f"/* overtake-mc: {shape.model.value} model, goal {shape.goal.value}; rendered from spec/, do not edit */",
        f"#define AV_CELL {AV_CELL}",
        f"#define DANGER {rules.danger_radius}",
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
        "byte i;  /* scratch index, reset to 0 at the end of every atomic step, so it is constant */",
        "",
        _INLINES,
        _goal_inline(goal.av_lane, goal.targets_behind, goal.nearest_target_offset, goal.oncoming_passed),
        "active proctype av() {",
        _load_literal(scenario, horizon) if scenario else _load_injected(),
        "  d_step { collide(); if :: !crashed -> printf(\"INIT \"); print_state(); goal_check() :: else -> skip fi;",
        "           assert(!reached); i = 0 }",
        "  do",
        *(_option(action) for action in ACTION_ORDER),
        "  od",
        "}",
    ]
    return "\n".join(parts) + "\n"


_INLINES = """inline collide() {
  if
  :: lane == LEFT ->
     i = 0; do :: i < nl -> crashed = crashed || left[i] == AV_CELL; i++ :: else -> break od
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


def _goal_inline(av_lane: Lane | None, targets_behind: bool, nearest: int | None, passed: bool) -> str:
    """The goal as a conjunction, field by field from the GoalRule."""
    lines = ["inline goal_check() {", "  reached = 1;"]
    if av_lane is not None:
        lines.append(f"  reached = reached && lane == {av_lane.name};")
    if targets_behind:
        lines.append("  i = ft; do :: i < ft + nt -> reached = reached && left[i] < AV_CELL; i++ :: else -> break od;")
    if nearest is not None:
        lines.append(f"  reached = reached && nt > 0 && left[ft] == AV_CELL + {nearest};")
    if passed:
        lines.append("  i = 0; do :: i < nr -> reached = reached && right[i] <= AV_CELL; i++ :: else -> break od;")
    lines.append("}")
    return "\n".join(lines)


def _option(action: Action) -> str:
    """One decision step as one atomic transition: guard, effect, check, ticks, goal."""
    rule = ACTION_RULES[action]
    guard = ["!crashed", "steps < horizon"]
    body = []
    if rule.from_lane is not None:
        guard.append(f"lane == {rule.from_lane.name}")
    if rule.changes_lane:
        guard.append("lc < MAX_LC")
        body += [f"lane = {rule.to_lane.name if rule.to_lane else 'lane'}", "lc++"]
    if rule.left_shift_cells:
        body.append(f"shift_left({rule.left_shift_cells})")
    body += ["steps++", "collide()"]
    body += ["tick()"] * rule.oncoming_ticks
    finish = (f'if :: !crashed -> printf("STEP {action.value} "); print_state(); goal_check(); assert(!reached)'
              " :: else -> skip fi; i = 0")
    return f"  :: d_step {{ {' && '.join(guard)} ->\n       {'; '.join(body)};\n       {finish} }}"


def _load_literal(scenario: Scenario, horizon: int | None) -> str:
    values = [f"lane = {LANE_CODE[scenario.lane]}", f"nl = {len(scenario.left_lane)}",
              f"nr = {len(scenario.right_lane)}", f"nt = {len(scenario.target_indices)}",
              f"ft = {scenario.target_indices[0] if scenario.target_indices else 0}",
              f"horizon = {scenario.horizon if horizon is None else horizon}"]
    values += [f"left[{i}] = {c}" for i, c in enumerate(scenario.left_lane)]
    values += [f"right[{i}] = {c}" for i, c in enumerate(scenario.right_lane)]
    return "  d_step { " + "; ".join(values) + " }"


def _load_injected() -> str:
    return f"""  c_code {{
    char *text = getenv("{ENV_VAR}"); char *end; long v[2 * MAXL + 8]; int n = 0, j, at;
    if (!text) {{ fprintf(stderr, "overtake: {ENV_VAR} is not set\\n"); exit(2); }}
    while (n < 2 * MAXL + 8) {{ v[n] = strtol(text, &end, 10); if (end == text) break; n++; text = end; }}
    at = 0; now.lane = v[at++]; now.nl = v[at++];
    for (j = 0; j < now.nl; j++) now.left[j] = v[at++];
    now.nr = v[at++];
    for (j = 0; j < now.nr; j++) now.right[j] = v[at++];
    now.nt = v[at++]; now.ft = v[at++]; now.horizon = v[at++];
    if (at != n || now.nl > MAXL || now.nr > MAXR || now.horizon > {MAX_HORIZON}) {{
      fprintf(stderr, "overtake: malformed {ENV_VAR}\\n"); exit(2); }}
  }};"""


def render_for(problem: Problem) -> str:
    """The literal model of one problem: what ``overtake promela`` writes."""
    return render(Shape(problem.model, goal_kind(problem.model, problem.scenario.lane)), problem.scenario,
                  problem.horizon)
