"""Render the sound model's Promela+C model from spec/: the Spin engine's own translation of ``spec.windows``.

The Promela state is the discrete part of a ``spec.sound.SoundState``: ``lane``, ``lc`` (lane
changes), ``steps``, ``t`` and ``d`` (time units and cells of nominal advance), ``first`` and
``last`` (speed indices, -1 none), ``moved`` (the lane the last action moved into: 0 none, 1
left, 2 right) and ``fol``, the followers, a bitmask over the same-direction list (bit ``i`` of
word ``i / 32``). The sensed vehicles, their intervals and the phantoms never change, so they are
C globals outside the state vector, built once when the verifier starts.

One decision step is one ``d_step``, as in ``promela.render``: its guard is the action's enabling
(lane, ``lc < MAX_LC``, ``steps < horizon``), its safety test a C function of the state; a refused
step leaves the state as it was (no successor), an allowed one applies the effect, prints the STEP
line (the display state: left cells ``c + t - d``, right cells ``c - t - d``) and violates
``assert(!reached)`` when the goal holds and the minimal-risk continuation is safe. The start: a
refused one has no successors; one where the plan may already end violates the assertion (the
empty plan).

What is compiled in is the verifier's shape (``SoundShape``): the model's rules, its goal, the grid
(each cell's extent, ``spec.cells``), the phantoms' lanes, the followers' words, ``EPS_M``. The sound
model's numbers are data, read from its table file when the verifier starts (``table_text``, from
``spec.windows.sound_table``): the windows (shapes, early windows, start windows, gains, speeds), the
required gap at each instant a condition binds (``SafetySpec.required_gap_m`` of the closing speed
this module forms from the instant's speed, the speed error and the lane's bound), the bounds, the
envelope, whether each window's end closes in (``MinimalRisk.closes_in``). The C code does the rest
itself: the vehicles' intervals (extents widened by the sensing error, then the phantoms from their
edges), their growth over time, the conditions of ``spec.windows``'s docstring, the followers, the
goal and the continuation. The scenario (AV lane, cells, targets, horizon, the phantoms' edges:
where a snapshot's view ended) and the table's path are read from ``OVERTAKE_SCENARIO`` when the
verifier starts (``promela.render.scenario_values``, then ``| path``), so one compiled verifier
serves every scenario, profile and measured start speed of its shape.

Spin refuses a ``c_expr`` that calls a function (it cannot tell a pure one), so each step's test
stores its answer in the C global ``sound_ok`` and the ``c_expr`` reads it.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

from spec.actions import ACTION_ORDER, ACTION_RULES, Action
from spec.cells import left_extent_m, oncoming_extent_m
from spec.constants import MAX_HORIZON
from spec.dynamics import Overtaken
from spec.envelope import CLOSING_EPS_MPS
from spec.errors import EngineError
from spec.escapes import ESCAPES
from spec.grid import Grid
from spec.lanes import Lane
from spec.models import GoalRule, ModelRules
from spec.scenario import Problem
from spec.sound import EPS_M, Checks, Sound, follower_limit_m, rear_binds
from spec.windows import (
    NO_SPEED,
    Binding,
    CutKey,
    EarlyKey,
    Instant,
    ShapeKey,
    Window,
    cut_shapes,
    shapes,
    sound_table,
)

ENV_VAR = "OVERTAKE_SCENARIO"
LANE_CODE = {Lane.LEFT: 0, Lane.RIGHT: 1}
MOVED_CODE = {None: 0, Lane.LEFT: 1, Lane.RIGHT: 2}
CONTINUATION = len(ACTION_ORDER)  # the action code of the minimal-risk continuation (action None)
WORD_BITS = 32
MAX_ESCAPE = max(len(e.actions) for e in ESCAPES)  # a sequence probed is a committed part and its escape
MAX_BATCH = 64  # sequences one run probes (a longer batch is run in parts)
TABLE_FORMAT = 4  # the table file's layout (table_text): a verifier reads only its own
TABLE_END = 271828  # the table's last number: a file cut short is refused


@dataclass(frozen=True, slots=True)
class SoundShape:
    """What a compiled verifier of the sound model is specialised for: the model's rules, its goal, the grid, the
    phantoms' lanes (in the order the scenario gives their edges) and the words of the followers' bitmask. The sound
    model's numbers (bounds, safety, tracking, start speed, minimal-risk manoeuvre) are read at the start from its
    table file (``table_text``): one verifier serves every profile and measured speed of its shape."""

    rules: ModelRules
    goal: GoalRule
    grid: Grid
    phantoms: tuple[Lane, ...]
    words: int = 1

    @property
    def name(self) -> str:
        """``sound-model-goal[-cell]-p<phantoms' lanes>-f<words>``: file and cache names."""
        cell = "" if self.grid.is_paper else f"-{float(self.grid.cell_m):g}m"
        lanes = "".join(lane.value[0] for lane in self.phantoms) or "none"
        return f"sound-{self.rules.kind.value}-{self.goal.kind.value}{cell}-p{lanes}-f{self.words}"

    def key_text(self) -> str:
        """The shape in full, for the verifier cache's key."""
        return repr(self)

    @property
    def left_phantoms(self) -> int:
        return sum(1 for lane in self.phantoms if lane is Lane.LEFT)

    @property
    def max_same(self) -> int:
        """The most same-direction vehicles the verifier holds: sensed ones, then the phantoms."""
        return min(self.words * WORD_BITS, self.grid.road_cells + 1 + self.left_phantoms)


def full_words(grid: Grid, sound: Sound) -> int:
    """The followers' words for the most same-direction vehicles a scenario on ``grid`` can have."""
    left_phantoms = sum(1 for p in sound.bounds.phantom_vehicles() if p.lane is Lane.LEFT)
    return -(-(grid.road_cells + 1 + left_phantoms) // WORD_BITS)


def table_sound(problem: Problem) -> Sound:
    """The sound model a verifier's table holds for ``problem``: its own, less the snapshot's view and where its
    sensors stood (the phantoms' edges are read with the scenario)."""
    sound = problem.scenario.sound
    if sound is None:
        raise ValueError("the problem's scenario has no sound model")
    return replace(sound, oncoming_view_m=None, sensors_ahead_m=0.0)


def shape_of(problem: Problem) -> SoundShape:
    """The verifier shape that serves ``problem``: one word of followers when its same-direction list fits, else as
    many as a full road needs. The identity check's paper cell rules (``Checks.PAPER_CELLS``) are the interpreter's
    only: an engine error."""
    sound = table_sound(problem)
    if sound.checks is not Checks.PHYSICAL:
        raise EngineError(f"spin answers the sound model's physical checks only, not {sound.checks.value!r} (the "
                          "identity check is the interpreter's)")
    lanes = tuple(p.lane for p in sound.bounds.phantom_vehicles())
    shape = SoundShape(problem.rules, problem.goal, problem.grid, lanes, 1)
    if len(problem.scenario.left_lane) + shape.left_phantoms > WORD_BITS:
        shape = SoundShape(problem.rules, problem.goal, problem.grid, lanes, full_words(problem.grid, sound))
    return shape


# -- C literals ------------------------------------------------------------------------------------------------
def _f(x: float) -> str:
    """A double exactly as Python holds it (``repr`` round-trips, and a finite float's always holds a "." or an
    exponent: a C double literal; gcc and ``strtod`` round decimal literals correctly)."""
    if not math.isfinite(x):
        raise ValueError(f"promela: a table number is not finite: {x}")
    return repr(float(x))


def _at(inst: Instant, gap_m: float) -> str:
    return f"{_f(inst.t_s)} {_f(inst.x_m)} {_f(gap_m)}"


def _piece(b: Binding, sound: Sound) -> str:
    """A piece: its start, and each condition's instant with the gap required there at that instant's worst
    closing speed (AHEAD: v + e_v - low; ONCOMING: v + e_v + high_o; behind: high - v + e_v)."""
    s, e_v, same, onc = sound.safety, sound.tracking.speed_mps, sound.bounds.same_mps, sound.bounds.oncoming_mps
    ahead = s.required_gap_m(b.ahead.v_mps + e_v - same.low_mps)
    oncoming = s.required_gap_m(b.oncoming.v_mps + e_v + onc.high_mps)
    behind = s.required_gap_m(same.high_mps - b.behind.v_mps + e_v)
    return (f"   {_f(b.start.t_s)} {_f(b.start.x_m)}  {_at(b.ahead, ahead)}  {_at(b.oncoming, oncoming)}  "
            f"{_at(b.behind, behind)}  {int(b.rear)}  {_f(b.end_s)} {_f(b.start.v_mps)} {_f(b.acc_mps2)}")


def _window(w: Window, sound: Sound) -> list[str]:
    """A window: its stretches, boundary, end (time, place, speed) and whether the minimal-risk manoeuvre from its
    end closes in; then each stretch (its occupancy's lanes and its pieces), a line each."""
    lines = [f" {len(w.stretches)} {_f(w.boundary.t_s)} {_f(w.boundary.x_m)} {_f(w.end.t_s)} {_f(w.end.x_m)} "
             f"{_f(w.end.v_mps)} "
             f"{int(sound.minimal_risk.closes_in(w.end.v_mps, sound.bounds.same_mps.low_mps))} "
             f"{int(rear_binds(sound.bounds, w.end.v_mps))}"]
    for st in w.stretches:
        lines.append(f"  {int(st.left)} {int(st.right)} {int(st.entering)} {int(st.at_start)} {len(st.pieces)}")
        lines += [_piece(b, sound) for b in st.pieces]
    return lines


def _action_code(action: Action | None) -> int:
    return CONTINUATION if action is None else ACTION_ORDER.index(action)


@functools.lru_cache(maxsize=64)
def table_text(sound: Sound, grid: Grid, hold_floor_mps: float | None = None, lane: Lane | None = None) -> str:
    """Every number of the sound model a verifier reads when it starts (``sound_load_table``), from
    ``spec.windows.sound_table``: the bounds, the envelope, each window (shapes, early windows, start windows) with
    the gap required at each instant a condition binds (``SafetySpec.required_gap_m`` of the closing speed this
    module forms from the instant's speed, the speed error and the lane's bound), the speeds and gains. Its first
    line names it; its second checks it against the verifier (format, road cells, actions, the phantoms' lanes), as
    do the grid's time unit and cell that open the third; a sentinel ends it. Doubles as Python's ``repr`` writes
    them: ``strtod`` reads each back exactly. ``hold_floor_mps``: the speed the minimal-risk manoeuvre brakes to in
    the scenarios it serves, ``lane`` their start's (``spec.windows.sound_table``); the fourth line holds what a
    vehicle measured to move by its own dynamics is checked with (the specification's gaps, the speed error, its
    rates of speed change, whether followers react)."""
    table = sound_table(sound, grid, hold_floor_mps, lane)
    change = sound.speed_change
    b, s, tr = sound.bounds, sound.safety, sound.tracking
    start = "" if sound.start_mps is None else f", measured start speed {sound.start_mps:g} m/s"
    phantoms = [LANE_CODE[p.lane] for p in b.phantom_vehicles()]
    lines = [f"# overtake-mc sound table: {sound.describe()}{start}; {grid.describe()}; rendered from spec/",
             " ".join(map(str, [TABLE_FORMAT, grid.road_cells, CONTINUATION, len(phantoms), *phantoms])),
             " ".join(_f(x) for x in (table.unit_s, table.cell_m, tr.position_m, s.vehicle_length_m,
                                      follower_limit_m(0.0, sound), b.same_mps.low_mps, b.same_mps.high_mps,
                                      b.oncoming_mps.low_mps, b.oncoming_mps.high_mps, sound.start_error_m(Lane.LEFT),
                                      sound.start_error_m(Lane.RIGHT))),
             " ".join(_f(x) for x in (s.min_gap_m, s.time_gap_s, tr.speed_mps, change.accel_mps2, change.brake_mps2,
                                      float(b.followers_react), CLOSING_EPS_MPS)) +
             f" {int(sound.overtaken is Overtaken.NO_ACCELERATION)}",
             f"{len(table.speeds_mps)} {table.start_speed}",
             " ".join(map(_f, table.speeds_mps)),
             " ".join(map(_f, table.gain_m)),
             " ".join(str(table.action_speed[a]) for a in ACTION_ORDER)]
    windows: list[list[str]] = []
    relative = [[[[-1] * 3 for _ in Lane] for _ in range(CONTINUATION + 1)] for _ in table.speeds_mps]
    unstarted = replace(sound, start_mps=None, sideways_s=0.0)
    shape_lines = [_shape_lines(unstarted, grid, v, i not in table.action_speed.values(), hold_floor_mps)
                   for i, v in enumerate(table.speeds_mps)]
    placed: dict[object, int] = {}  # each shape's and early window's index, for their cut windows
    for key in sorted(table.relative, key=_shape_order):
        before, action, lane, moved = key
        relative[before][_action_code(action)][LANE_CODE[lane]][MOVED_CODE[moved]] = placed[key] = len(windows)
        windows.append(shape_lines[before][action, lane, moved])
    early = []
    for at, w in sorted(table.early.items(), key=lambda kv: _early_order(kv[0])):
        lane, t, d, first, last, moved, action = at
        early.append(f"{LANE_CODE[lane]} {t} {d} {first} {last} {MOVED_CODE[moved]} {_action_code(action)} "
                     f"{len(windows)}")
        placed[at] = len(windows)
        windows.append(_window(w, sound))
    starts = []
    for lane in Lane:
        starts.append(str(len(windows)))
        windows.append(_window(table.start[lane], sound))
    cuts = []
    cut_lines = {i: _cut_lines(unstarted, grid, table.speeds_mps[i], hold_floor_mps)
                 for i in set(table.action_speed.values())} if table.relative_cut else {}
    for (key, following), _ in sorted(table.relative_cut.items(), key=lambda kv: (_shape_order(kv[0][0]), kv[0][1])):
        before, step, lane, moved = key
        if step is None:
            raise ValueError("promela: a cut continuation window (only steps are cut)")
        cuts.append(f"{placed[key]} {following} {len(windows)}")
        windows.append(cut_lines[before][step, lane, moved, table.speeds_mps[following]])
    for (at, following), w in sorted(table.early_cut.items(), key=lambda kv: (_early_order(kv[0][0]), kv[0][1])):
        cuts.append(f"{placed[at]} {following} {len(windows)}")
        windows.append(_window(w, sound))
    lines.append(str(len(windows)))
    lines += [line for w in windows for line in w]
    lines += [" ".join(str(k) for by_action in by_speed for by_lane in by_action for k in by_lane)
              for by_speed in relative]
    lines += [str(len(early)), *early, " ".join(starts), str(len(cuts)), *cuts, str(TABLE_END)]
    return "\n".join(lines) + "\n"


def _shape_order(key: ShapeKey) -> tuple[int, ...]:
    before, action, lane, moved = key
    return before, _action_code(action), LANE_CODE[lane], MOVED_CODE[moved]


def _early_order(key: EarlyKey) -> tuple[int, ...]:
    lane, t, d, first, last, moved, action = key
    return LANE_CODE[lane], t, d, first, last, MOVED_CODE[moved], _action_code(action)


@functools.lru_cache(maxsize=64)
def _cut_lines(sound: Sound, grid: Grid, before_mps: float, hold_floor_mps: float | None) -> dict[CutKey, list[str]]:
    """The table's lines of the cut shapes after ``before_mps`` (``spec.windows.cut_shapes``), written once."""
    return {key: _window(w, sound) for key, w in cut_shapes(sound, grid, before_mps, hold_floor_mps).items()}


@functools.lru_cache(maxsize=64)
def _shape_lines(sound: Sound, grid: Grid, before_mps: float, continuation_only: bool,
                 hold_floor_mps: float | None) -> dict[
        tuple[Action | None, Lane, Lane | None], list[str]]:
    """The table's lines of the shapes after ``before_mps`` (``spec.windows.shapes``; ``sound`` without a start
    speed), written once: a new measured start speed adds its own continuation and early windows only."""
    return {key: _window(w, sound) for key, w in shapes(sound, grid, before_mps, continuation_only,
                                                        hold_floor_mps).items()}


def _tables(shape: SoundShape) -> str:
    """The verifier's constants (grid, phantoms' lanes, cell extents) and the table's variables, set when the table
    is read (``sound_load_table``)."""
    grid = shape.grid
    phantoms = [f"{{{LANE_CODE[lane]}, 0.0}}" for lane in shape.phantoms] or ["{0, 0.0}"]
    left_ext = ",\n".join(
        "  {" + ", ".join(f"{{{_f(lo)}, {_f(hi)}}}" for lo, hi in (left_extent_m(c, lane, grid)
                                                                 for c in range(grid.road_cells + 1))) + "}"
        for lane in Lane)
    onc_ext = ", ".join(f"{{{_f(lo)}, {_f(hi)}}}" for lo, hi in (oncoming_extent_m(c, grid)
                                                                for c in range(grid.road_cells + 1)))
    into_left = ", ".join(str(int(ACTION_RULES[a].to_lane is Lane.LEFT)) for a in ACTION_ORDER)
    right_phantoms = len(shape.phantoms) - shape.left_phantoms
    return "\n".join([
        f"#define TABLE_FORMAT {TABLE_FORMAT}",
        f"#define TABLE_END {TABLE_END}",
        f"#define NO_SPEED {NO_SPEED}",
        f"#define N_PHANTOMS {len(shape.phantoms)}",
        f"#define ROAD_CELLS {grid.road_cells}",
        f"#define MAX_SAME {shape.max_same}",
        f"#define MAX_ONC {grid.road_cells + 1 + right_phantoms}",
        f"#define MAX_HORIZON {MAX_HORIZON}",
        f"#define CONTINUATION {CONTINUATION}",
        "c_decl {",
        "typedef struct { double t, x, gap; } SoundAt;  /* an instant of the reference, the gap required there */",
        "typedef struct { double t0, x0; SoundAt ahead, oncoming, behind; int rear; double t1, v0, acc; } SoundPiece;",
        "typedef struct { int left, right, entering, at_start, n; SoundPiece *p; } SoundStretch;",
        "typedef struct { int n; SoundStretch *s; double bt, bx, et, ex, ev; int closes, rear_closes; } SoundWindow;",
        "/* a stretch of constant acceleration of a measured vehicle's least or most travel (spec.dynamics.Phase) */",
        "typedef struct { double t0, t1, travel, speed, accel; } SoundPhase;",
        "/* a vehicle's own dynamics (spec.dynamics.Dynamics), when its speed was measured: measured 0 otherwise */",
        "typedef struct { int measured, ns, nf; SoundPhase slow[2], fast[2]; double low, top; } SoundMotion;",
        "typedef struct { int lane, t, d, first, last, moved, action, window; } SoundEarly;",
        "typedef struct { int lane; double dx; } SoundPhantom;  /* dx: read with the scenario (its view) */",
        f"static const double EPS_M = {_f(EPS_M)};",
        "/* the sound model's numbers, read from its table when the verifier starts (sound_load_table) */",
        f"static const double UNIT_S = {_f(float(grid.time_unit_s))}, CELL_M = {_f(grid.cell)};  /* the grid's */",
        "static double E_X, LEN, FOLLOWER_M, SAME_LOW, SAME_HIGH, ONC_LOW, ONC_HIGH;",
        "static double START_ERROR_M, START_ERROR_ONC_M;  /* sensing error + age: left lane, right lane */",
        "static double G_MIN, TAU, E_V, A_MAX, B_MAX, FOLLOWERS_REACT, CLOSING_EPS;  /* for measured vehicles */",
        "static int NO_ACCELERATION;  /* measured same-direction vehicles do not speed up while the AV is out */",
        "static int held_passing;  /* that profile, and a measured same-direction vehicle it speaks of */",
        "static int N_SPEEDS, START_SPEED, N_WINDOWS, N_EARLY, START_WINDOW[2], ACTION_SPEED[CONTINUATION];",
        "static double *SPEEDS_MPS, *GAIN_M;",
        "static SoundWindow *WINDOWS;",
        "static SoundEarly *EARLY;",
        "/* the shapes: the window (-1: none) by speed before, action (CONTINUATION: none), lane, moved */",
        "static short *RELATIVE_;",
        "#define RELATIVE(b, a, l, m) RELATIVE_[(((b) * (CONTINUATION + 1) + (a)) * 2 + (l)) * 3 + (m)]",
        "/* a step's window cut where the ramp into a following action of another speed starts (-1: none), by the",
        "   window and the following action's speed: the commitment semantics' sequences known whole */",
        "static int *CUT_;",
        "#define CUT(w, f) CUT_[(w) * N_SPEEDS + (f)]",
        "/* the probe (promela.render.Probe): 0 the plan search; else the sequences asked about, one per path (the",
        "   path's seqid): one of its kind, or (SQ_BATCH) several, each of its own kind, each one held printed */",
        "#define SQ_ESCAPE 1",
        "#define SQ_WHOLE 2",
        "#define SQ_START 3",
        "#define SQ_WALK 4",
        "#define SQ_BATCH 5",
        f"#define MAX_SEQ {MAX_HORIZON + MAX_ESCAPE}",
        f"#define MAX_BATCH {MAX_BATCH}",
        "static int SQ_PROBE, N_BATCH, B_KIND[MAX_BATCH], B_LEN[MAX_BATCH], B_SEQ[MAX_BATCH][MAX_SEQ];",
        "#define SEQ_LEN B_LEN[now.seqid]",
        "#define SEQ_KIND B_KIND[now.seqid]",
        "#define SEQ_AT(k) B_SEQ[now.seqid][k]",
        f"static const int INTO_LEFT[CONTINUATION] = {{{into_left}}};",
        f"static SoundPhantom PHANTOMS[N_PHANTOMS + 1] = {{{', '.join(phantoms)}}};",
        "/* where a vehicle in a cell can be, metres ahead of the AV: same direction (by the AV lane), oncoming */",
        "static const double LEFT_EXTENT[2][ROAD_CELLS + 1][2] = {",
        left_ext,
        "};",
        f"static const double ONCOMING_EXTENT[ROAD_CELLS + 1][2] = {{{onc_ext}}};",
        "/* the scenario, set once when the verifier starts (sound_load) */",
        "static double S_LO[MAX_SAME], S_HI[MAX_SAME], O_LO[MAX_ONC], O_HI[MAX_ONC];",
        "static SoundMotion S_MOT[MAX_SAME], O_MOT[MAX_ONC];",
        "static int n_same, n_onc, n_left, n_right, n_targets, first_target;",
        "static int left_cells[ROAD_CELLS + 1], right_cells[ROAD_CELLS + 1];",
        "static unsigned step_fol[FW];  /* the followers during the step just tested */",
        "static int sound_ok;  /* the answer of the step just tested */",
        "}",
    ])


def _goal(goal: GoalRule) -> str:
    """The goal at the continuation window's boundary (x, t), field by field from the GoalRule (``goal_holds``)."""
    lines = []
    if goal.av_lane is not None:
        lines.append(f"\tif (now.lane != {LANE_CODE[goal.av_lane]}) return 0;")
    if goal.targets_behind:
        lines.append("\tfor (i = first_target; i < first_target + n_targets; i++)\n"
                     "\t\tif (sound_same_high(i, t) > x - E_X - LEN) return 0;")
    if goal.nearest_target_m is not None:
        lines.append("\tif (n_targets == 0) return 0;\n"
                     "\ti = first_target;\n"
                     "\tif (sound_same_low(i, t) - (x + E_X) - LEN < 0\n"
                     f"\t||  sound_same_high(i, t) - (x - E_X) - LEN > {_f(float(goal.nearest_target_m))}) return 0;")
    if goal.oncoming_passed:
        lines.append("\tfor (i = 0; i < n_right; i++) if (!sound_passed(i, x, t)) return 0;  /* sensed ones only */")
    return "\n".join(lines)


_FUNCTIONS = r"""c_code {
\#include <setjmp.h>  /* "\#": passed to pan.c, not read by spin's preprocessor */
static int sound_follows(const unsigned *fol, int i) { return (fol[i / 32] >> (i % 32)) & 1u; }

/* a measured vehicle's motion (spec.dynamics): the phase of a travel bound at t, its travel and speed then */
static const SoundPhase *sound_phase(const SoundPhase *ph, int n, double t)
{	int k;
	for (k = 0; k < n; k++) { if (t < ph[k].t1) { return &ph[k]; } }
	return &ph[n - 1];
}

static double sound_travel(const SoundPhase *p, double t)
{	double s = t - p->t0;
	return p->travel + p->speed * s + p->accel * s * s / 2;
}

static double sound_speed(const SoundPhase *p, double t) { return p->speed + p->accel * (t - p->t0); }

/* speeding up at A_MAX from high to its top m->top, or until hold_s (infinite: never held), then holding the speed
   reached (spec.dynamics._fastest) */
static void sound_fast(SoundMotion *m, double high, double hold_s)
{	double top_s, reached;
	if (high >= m->top || hold_s <= 0)
	{	m->nf = 1; m->fast[0].t0 = 0.0; m->fast[0].t1 = __builtin_inf(); m->fast[0].travel = 0.0;
		m->fast[0].speed = high; m->fast[0].accel = 0.0;
		return;
	}
	top_s = (m->top - high) / A_MAX;
	if (hold_s < top_s) { top_s = hold_s; }
	reached = high + A_MAX * top_s;
	m->nf = 2; m->fast[0].t0 = 0.0; m->fast[0].t1 = top_s; m->fast[0].travel = 0.0; m->fast[0].speed = high;
	m->fast[0].accel = A_MAX;
	m->fast[1].t0 = top_s; m->fast[1].t1 = __builtin_inf(); m->fast[1].travel = (high + reached) / 2 * top_s;
	m->fast[1].speed = reached; m->fast[1].accel = 0.0;
}

/* braking at B_MAX from low to a standstill; speeding up at A_MAX from high to its top (spec.dynamics) */
static void sound_motion(SoundMotion *m, double low, double high, double top)
{	double stop, most = top > high ? top : high;
	m->measured = 1; m->low = low; m->top = most;
	if (low <= 0)
	{	m->ns = 1; m->slow[0].t0 = 0.0; m->slow[0].t1 = __builtin_inf(); m->slow[0].travel = 0.0;
		m->slow[0].speed = 0.0; m->slow[0].accel = 0.0;
	} else
	{	stop = low / B_MAX;
		m->ns = 2; m->slow[0].t0 = 0.0; m->slow[0].t1 = stop; m->slow[0].travel = 0.0; m->slow[0].speed = low;
		m->slow[0].accel = -B_MAX;
		m->slow[1].t0 = stop; m->slow[1].t1 = __builtin_inf(); m->slow[1].travel = low * low / (2 * B_MAX);
		m->slow[1].speed = 0.0; m->slow[1].accel = 0.0;
	}
	sound_fast(m, high, __builtin_inf());
}

static double sound_least(const SoundMotion *m, double t) { return sound_travel(sound_phase(m->slow, m->ns, t), t); }
static double sound_most(const SoundMotion *m, double t) { return sound_travel(sound_phase(m->fast, m->nf, t), t); }

/* where a vehicle can be at t: the least and the most of a same-direction one, of an oncoming one */
static double sound_same_low(int i, double t)
{	return S_MOT[i].measured ? S_LO[i] + sound_least(&S_MOT[i], t) : S_LO[i] + SAME_LOW * t;
}
static double sound_same_high(int i, double t)
{	return S_MOT[i].measured ? S_HI[i] + sound_most(&S_MOT[i], t) : S_HI[i] + SAME_HIGH * t;
}
static double sound_onc_high(int j, double t)
{	return O_MOT[j].measured ? O_HI[j] - sound_least(&O_MOT[j], t) : O_HI[j] - ONC_LOW * t;
}

/* a same-direction vehicle clear ahead of the AV at (x, t) for every position: held to AHEAD */
static int sound_held_ahead(int i, double x, double t) { return sound_same_low(i, t) - LEN >= x + E_X; }

/* an oncoming vehicle certainly past the AV at (x, t) */
static int sound_passed(int j, double x, double t) { return sound_onc_high(j, t) + LEN <= x - E_X - EPS_M; }

static int sound_ahead_refused(int i, const SoundAt *a, double dt, double dx)
{	return S_LO[i] + SAME_LOW * (a->t + dt) < a->x + dx + E_X + LEN + a->gap + EPS_M;
}

static int sound_oncoming_refused(int j, const SoundAt *a, double dt, double dx)
{	return O_LO[j] - ONC_HIGH * (a->t + dt) < a->x + dx + E_X + LEN + a->gap + EPS_M;
}

static int sound_behind_clear(int i, const SoundAt *a, double dt, double dx)
{	return S_HI[i] + SAME_HIGH * (a->t + dt) <= a->x + dx - E_X - LEN - a->gap - EPS_M;
}

/* the most of a s^2 + b s + c over [0, span] */
static double sound_quad_max(double a, double b, double c, double span)
{	double best = c, end = a * span * span + b * span + c, s;
	if (end > best) { best = end; }
	if (a < 0)
	{	s = -b / (2 * a);
		if (0 < s && s < span && a * s * s + b * s + c > best) { best = a * s * s + b * s + c; }
	}
	return best;
}

#define OWN_AHEAD 0
#define OWN_ONCOMING 1
#define OWN_BEHIND 2  /* a cut-in's, or a follower's */

/* a measured vehicle's threshold over the reference piece (t0, t1, x0, v0, acc) (spec.sound.SoundRules._own_need):
   AHEAD and ONCOMING the least start lo, BEHIND the most start hi; exact over each phase of its worst motion */
static double sound_own_need(int conflict, const SoundMotion *m, double pt0, double pt1, double px0, double pv0,
                             double pacc)
{	const SoundPhase *ph = conflict == OWN_AHEAD ? m->slow : m->fast;
	int n = conflict == OWN_AHEAD ? m->ns : m->nf, k;
	double best = -__builtin_inf(), u0, u1, s0, x, v, span, dm, dv, da, c, b1, a, f1, f2;
	for (k = 0; k < n; k++)
	{	u0 = pt0 > ph[k].t0 ? pt0 : ph[k].t0;
		u1 = pt1 < ph[k].t1 ? pt1 : ph[k].t1;
		if (u1 < u0 || (u1 == u0 && pt1 > pt0)) { continue; }
		s0 = u0 - pt0;
		x = px0 + pv0 * s0 + pacc * s0 * s0 / 2;
		v = pv0 + pacc * (u0 - pt0);
		span = u1 - u0;
		dm = sound_travel(&ph[k], u0); dv = sound_speed(&ph[k], u0); da = ph[k].accel;
		if (conflict == OWN_AHEAD)
		{	c = x + E_X + LEN - dm; b1 = v - dv; a = (pacc - da) / 2;
			f1 = sound_quad_max(a, b1, c + G_MIN, span);
			f2 = sound_quad_max(a, b1 + TAU * (pacc - da), c + TAU * (v + E_V - dv), span);
		} else if (conflict == OWN_ONCOMING)
		{	c = x + E_X + LEN + dm; b1 = v + dv; a = (pacc + da) / 2;
			f1 = sound_quad_max(a, b1, c + G_MIN, span);
			f2 = sound_quad_max(a, b1 + TAU * (pacc + da), c + TAU * (v + E_V + dv), span);
		} else
		{	c = -(x - E_X - LEN - dm); b1 = -(v - dv); a = -(pacc - da) / 2;
			f1 = sound_quad_max(a, b1, c + G_MIN, span);
			f2 = sound_quad_max(a, b1 + TAU * (da - pacc), c + TAU * (dv - v + E_V), span);
		}
		if (f1 > best) { best = f1; }
		if (f2 > best) { best = f2; }
	}
	return conflict == OWN_BEHIND ? -best : best;
}

static double sound_piece_need(int conflict, const SoundMotion *m, const SoundPiece *p, double dt, double dx)
{	return sound_own_need(conflict, m, p->t0 + dt, p->t1 + dt, p->x0 + dx, p->v0, p->acc);
}

/* whether followers that keep their speed close in on the reference at the speed v (spec.sound.rear_binds): a
   measured one up to its own top */
static int sound_rear_binds(int i, double v)
{	double top = S_MOT[i].measured && S_MOT[i].top > SAME_HIGH ? S_MOT[i].top : SAME_HIGH;
	return FOLLOWERS_REACT == 0.0 && v < top - CLOSING_EPS;
}

/* a stretch of one occupancy, moved by (dt, dx): whether some vehicle breaks its condition; held_s (negative: none):
   a move back from the passing lane under the no-acceleration profile, measured vehicles not speeding up since then
   (spec.sound.SoundRules._check_entering) */
static int sound_stretch_refused(const SoundStretch *s, double dt, double dx, const unsigned *fol, double held_s)
{	int i, k, ahead, behind;
	double need, allow, bound, slowest;
	const SoundPiece *p;
	SoundMotion held;
	if (s->left && s->entering)
	{	for (i = 0; i < n_same; i++)  /* each one certainly ahead at every piece, or certainly behind */
		{	ahead = 1; behind = 1;
			if (S_MOT[i].measured)
			{	need = -__builtin_inf(); allow = __builtin_inf();
				held = S_MOT[i];
				if (held_s >= 0) { sound_fast(&held, S_MOT[i].fast[0].speed, held_s); }
				for (k = 0; k < s->n; k++)  /* the most lo needed over the move, the least hi allowed */
				{	p = &s->p[k];
					bound = sound_piece_need(OWN_AHEAD, &S_MOT[i], p, dt, dx);
					if (bound > need) { need = bound; }
					bound = sound_piece_need(OWN_BEHIND, &held, p, dt, dx);
					if (bound < allow) { allow = bound; }
				}
				ahead = S_LO[i] >= need + EPS_M;
				behind = S_HI[i] <= allow - EPS_M;
			} else
			{	for (k = 0; k < s->n; k++)
				{	p = &s->p[k];
					if (sound_ahead_refused(i, &p->ahead, dt, dx)) { ahead = 0; }
					if (!sound_behind_clear(i, &p->behind, dt, dx)) { behind = 0; }
			}	}
			if (s->at_start)  /* already in the lane: one that cannot be clear ahead follows */
			{	behind = S_HI[i] <= s->p[0].x0 + dx + FOLLOWER_M - EPS_M;
			}
			if (!ahead && !behind) { return 1; }
		}
	} else if (s->left)
	{	for (k = 0; k < s->n; k++)
		{	p = &s->p[k];
			slowest = p->v0 < p->v0 + p->acc * (p->t1 - p->t0) ? p->v0 : p->v0 + p->acc * (p->t1 - p->t0);
			for (i = 0; i < n_same; i++)
			{	if (!sound_follows(fol, i))
				{	if (sound_held_ahead(i, p->x0 + dx, p->t0 + dt)
					&&  (S_MOT[i].measured ? S_LO[i] < sound_piece_need(OWN_AHEAD, &S_MOT[i], p, dt, dx) + EPS_M
						: sound_ahead_refused(i, &p->ahead, dt, dx))) { return 1; }
				} else if (S_MOT[i].measured)  /* BEHIND: a follower that keeps its speed */
				{	if (sound_rear_binds(i, slowest)
					&&  S_HI[i] > sound_piece_need(OWN_BEHIND, &S_MOT[i], p, dt, dx) - EPS_M) { return 1; }
				} else if (p->rear && !sound_behind_clear(i, &p->behind, dt, dx)) { return 1; }
		}	}
	}
	if (s->right)
	{	for (k = 0; k < s->n; k++)
		{	p = &s->p[k];
			for (i = 0; i < n_onc; i++)
			{	if (!sound_passed(i, p->x0 + dx, p->t0 + dt)
				&&  (O_MOT[i].measured ? O_LO[i] < sound_piece_need(OWN_ONCOMING, &O_MOT[i], p, dt, dx) + EPS_M
					: sound_oncoming_refused(i, &p->oncoming, dt, dx))) { return 1; }
		}	}
	}
	return 0;
}

/* the window of an action (CONTINUATION: none) from the current state, and how far it is moved */
static const SoundWindow *sound_window(int action, double *dt, double *dx)
{	int k, first = now.first, before;
	const SoundEarly *e;
	for (k = 0; k < N_EARLY; k++)
	{	e = &EARLY[k];
		if (e->lane == now.lane && e->t == now.t && e->d == now.d && e->first == now.first
		&&  e->last == now.last && e->moved == now.moved && e->action == action)
		{	*dt = 0.0; *dx = 0.0;
			return &WINDOWS[e->window];
	}	}
	if (first < 0) { first = action == CONTINUATION ? START_SPEED : ACTION_SPEED[action]; }
	before = now.last < 0 ? first : now.last;
	k = RELATIVE(before, action, now.lane, now.moved);
	if (k < 0)
	{	fprintf(stderr, "overtake: no window for action %d from lane %d, moved %d\n", action, now.lane, now.moved);
		exit(3);
	}
	*dt = now.t * UNIT_S;
	*dx = now.d * CELL_M + GAIN_M[first];
	return &WINDOWS[k];
}

/* whether an action keeps every condition over its window; its followers are left in step_fol */
static int sound_step_ok(int action)
{	double dt, dx, held_s = -1.0;
	int i, k, next, cut;
	const SoundWindow *w;
	if (SQ_PROBE && (now.steps >= SEQ_LEN || SEQ_AT(now.steps) != action)) { return 0; }  /* off the sequence */
	if (SQ_PROBE && SEQ_KIND == SQ_WALK)  /* the display states along it: no check */
	{	for (k = 0; k < FW; k++) { step_fol[k] = (unsigned) now.fol[k]; }
		return 1;
	}
	w = sound_window(action, &dt, &dx);
	next = SQ_PROBE && now.steps + 1 < SEQ_LEN ? SEQ_AT(now.steps + 1) : -1;
	if (next >= 0 && ACTION_SPEED[next] != ACTION_SPEED[action])  /* known to follow: the window ends at its ramp */
	{	cut = CUT((int) (w - WINDOWS), ACTION_SPEED[next]);
		if (cut < 0)
		{	fprintf(stderr, "overtake: no cut window for action %d before action %d\n", action, next);
			exit(3);
		}
		w = &WINDOWS[cut];
	}
	if (INTO_LEFT[action] && held_passing)  /* when the passing window began (spec.sound.SoundRules.passing_from_s) */
	{	held_s = now.out >= 0 ? now.out * UNIT_S : (now.lane == RIGHT ? 0.0 : -1.0);
	}
	for (k = 0; k < FW; k++) { step_fol[k] = (unsigned) now.fol[k]; }
	if (INTO_LEFT[action])  /* those not held ahead at the boundary follow the AV from now on */
	{	for (k = 0; k < FW; k++) { step_fol[k] = 0; }
		for (i = 0; i < n_same; i++)
		{	if (!sound_held_ahead(i, w->bx + dx, w->bt + dt)) { step_fol[i / 32] |= 1u << (i % 32); }
	}	}
	for (k = 0; k < w->n; k++)
	{	if (sound_stretch_refused(&w->s[k], dt, dx, step_fol, held_s)) { return 0; }
	}
	return 1;
}

/* an action's speed index: the first one of the plan and the last one */
static void sound_speeds(int action)
{	if (now.first == NO_SPEED) { now.first = ACTION_SPEED[action]; }
	now.last = ACTION_SPEED[action];
}

static void sound_take_followers(void)
{	int k;
	for (k = 0; k < FW; k++) { now.fol[k] = (int) step_fol[k]; }
}

/* whether a plan may end here: the goal holds for every position, and the minimal-risk manoeuvre is safe for ever;
   under a probe, where the sequence ends (an escape's: safe for ever, no goal; a walk's: its steps alone) */
static int sound_holds(void)
{	double dt, dx, x, t, stop;
	int i, k;
	const SoundWindow *w;
	if (SQ_PROBE == SQ_START) { return 1; }  /* called only from a start not refused */
	if (SQ_PROBE && now.steps != SEQ_LEN) { return 0; }
	if (SQ_PROBE && SEQ_KIND == SQ_WALK) { return 1; }
	w = sound_window(CONTINUATION, &dt, &dx);
	x = w->bx + dx;
	t = w->bt + dt;
	if (!SQ_PROBE || SEQ_KIND == SQ_WHOLE)
	{
GOAL
	}
	for (k = 0; k < w->n; k++)
	{	if (sound_stretch_refused(&w->s[k], dt, dx, (const unsigned *) now.fol, -1.0)) { return 0; }
	}
	x = w->ex + dx;
	t = w->et + dt;
	if (now.lane == RIGHT)
	{	for (i = 0; i < n_onc; i++) { if (!sound_passed(i, x, t)) { return 0; } }
	} else
	{	for (i = 0; i < n_same; i++)
		{	if (sound_follows((const unsigned *) now.fol, i))
			{	if (S_MOT[i].measured ? sound_rear_binds(i, w->ev) : w->rear_closes) { return 0; }
				continue;
			}
			if (!sound_held_ahead(i, x, t)) { continue; }
			if (!S_MOT[i].measured)
			{	if (w->closes) { return 0; }
				continue;
			}
			if (w->ev > 0.0 + CLOSING_EPS) { return 0; }  /* it may stop: the AV must stand too */
			stop = S_MOT[i].low / B_MAX;  /* still braking when the manoeuvre ends: AHEAD until it stands */
			if (stop > t && S_LO[i] < sound_own_need(OWN_AHEAD, &S_MOT[i], t, stop, x, w->ev, 0.0) + EPS_M)
			{	return 0;
			}
	}	}
	return 1;
}

/* whether the path ends here (the assertion's violation: the plan, or the probe's one sequence held); a batch's
   sequence held is printed instead, and every path of the batch is searched */
static int sound_done(void)
{	int held = sound_holds();
	if (SQ_PROBE != SQ_BATCH) { return held; }
	if (held) { printf("HELD %d\n", now.seqid); }
	return 0;
}

/* the start, an instant: refused or not; those not held ahead there follow the AV */
static void sound_start(void)
{	const SoundWindow *w = &WINDOWS[START_WINDOW[now.lane]];
	SoundStretch in_lane;
	unsigned none[FW];
	int i, k;
	for (k = 0; k < FW; k++) { none[k] = 0; now.fol[k] = 0; }
	for (i = 0; i < n_same; i++)
	{	if (!sound_held_ahead(i, w->bx, w->bt)) { now.fol[i / 32] |= (int) (1u << (i % 32)); }
	}
	now.refused = 0;
	for (k = 0; k < w->n; k++)
	{	if (sound_stretch_refused(&w->s[k], 0.0, 0.0, none, -1.0)) { now.refused = 1; }
		if (w->s[k].left && w->s[k].at_start)  /* then as in the lane, with its followers (start_violation) */
		{	in_lane = w->s[k];
			in_lane.entering = 0;
			if (sound_stretch_refused(&in_lane, 0.0, 0.0, (const unsigned *) now.fol, -1.0)) { now.refused = 1; }
	}	}
}

/* the display state: lane lc steps | left cells c + t - d | right cells c - t - d */
static void sound_show(const char *what)
{	int j;
	Printf("%s %d %d %d |", what, now.lane, now.lc, now.steps);
	for (j = 0; j < n_left; j++) { Printf(" %d", left_cells[j] + now.t - now.d); }
	Printf(" |");
	for (j = 0; j < n_right; j++) { Printf(" %d", right_cells[j] - now.t - now.d); }
	Printf("\n");
}

static void sound_malformed(const char *why)
{	fprintf(stderr, "overtake: malformed ENV_NAME (%s)\n", why);
	exit(2);
}

static const char *table_path;
static char *table_at;
static char *table_loaded = NULL;  /* the path of the table the globals hold, once read whole */
static void **table_blocks = NULL;  /* the blocks its reading allocated: freed when another table is read */
static int n_table_blocks = 0, max_table_blocks = 0;
static jmp_buf *table_trap = NULL;  /* set while a served verifier reads a table before its fork (sound_prepare) */

/* a table that will not read, while the server reads it (sound_prepare): back there, the run reports it */
static void table_escape(void)
{	if (table_trap) { longjmp(*table_trap, 1); }
}

static void sound_bad_table(const char *why)
{	table_escape();
	fprintf(stderr, "overtake: the sound model's table %s is not this verifier's (%s)\n", table_path, why);
	exit(2);
}

static void table_no_memory(void)
{	table_escape();
	fprintf(stderr, "overtake: out of memory reading the sound model's table\n");
	exit(2);
}

static double table_number(void)
{	char *end;
	double x = strtod(table_at, &end);
	if (end == table_at) { sound_bad_table("too few numbers"); }
	table_at = end;
	return x;
}

static int table_int(int lo, int hi, const char *what)
{	double x = table_number();
	if (!(x >= lo && x <= hi) || x != (double) (int) x) { sound_bad_table(what); }
	return (int) x;
}

static void *table_alloc(int n, size_t size)
{	void *p = calloc(n > 0 ? (size_t) n : 1, size), **more;
	int grown = max_table_blocks ? 2 * max_table_blocks : 64;
	if (!p) { table_no_memory(); }
	if (n_table_blocks == max_table_blocks)
	{	more = realloc(table_blocks, (size_t) grown * sizeof(void *));
		if (!more) { free(p); table_no_memory(); }
		table_blocks = more;
		max_table_blocks = grown;
	}
	table_blocks[n_table_blocks++] = p;
	return p;
}

static void table_at_instant(SoundAt *a)
{	a->t = table_number(); a->x = table_number(); a->gap = table_number();
}

/* the sound model's numbers (promela.sound.table_text): the header checked against this verifier, the bounds and
   the envelope, the speeds, every window, the shapes, the early windows, the start windows, the end */
static void sound_load_table(const char *path)
{	FILE *f;
	long size;
	char *text;
	int i, j, k, n;
	SoundWindow *w;
	SoundStretch *st;
	SoundPiece *p;
	table_path = path;
	if (table_loaded != NULL && strcmp(table_loaded, path) == 0) { return; }  /* read by the server before its fork */
	free(table_loaded);
	table_loaded = NULL;
	while (n_table_blocks > 0) { free(table_blocks[--n_table_blocks]); }
	f = fopen(path, "rb");
	if (!f)
	{	table_escape();
		fprintf(stderr, "overtake: cannot read the sound model's table %s\n", path);
		exit(2);
	}
	if (fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0)
	{	fclose(f);
		sound_bad_table("unreadable");
	}
	text = table_alloc((int) size + 1, 1);
	if (fread(text, 1, (size_t) size, f) != (size_t) size) { fclose(f); sound_bad_table("unreadable"); }
	fclose(f);
	text[size] = 0;
	table_at = text;
	if (*table_at == '#') { while (*table_at && *table_at != '\n') { table_at++; } }  /* its name */
	if (table_int(0, 1000000, "format") != TABLE_FORMAT) { sound_bad_table("another format"); }
	if (table_int(0, 1000000, "road cells") != ROAD_CELLS) { sound_bad_table("another grid"); }
	if (table_int(0, 1000000, "actions") != CONTINUATION) { sound_bad_table("other actions"); }
	if (table_int(0, 1000000, "phantoms") != N_PHANTOMS) { sound_bad_table("other phantoms"); }
	for (j = 0; j < N_PHANTOMS; j++)
	{	if (table_int(0, 1, "a phantom's lane") != PHANTOMS[j].lane) { sound_bad_table("other phantoms"); }
	}
	if (table_number() != UNIT_S || table_number() != CELL_M) { sound_bad_table("another grid"); }
	E_X = table_number(); LEN = table_number();
	FOLLOWER_M = table_number(); SAME_LOW = table_number(); SAME_HIGH = table_number();
	ONC_LOW = table_number(); ONC_HIGH = table_number(); START_ERROR_M = table_number();
	START_ERROR_ONC_M = table_number();
	G_MIN = table_number(); TAU = table_number(); E_V = table_number(); A_MAX = table_number();
	B_MAX = table_number(); FOLLOWERS_REACT = table_number(); CLOSING_EPS = table_number();
	NO_ACCELERATION = table_int(0, 1, "the no-acceleration profile");
	if (!(A_MAX > 0 && B_MAX > 0)) { sound_bad_table("rates of speed change"); }
	N_SPEEDS = table_int(1, 1000, "speeds");
	START_SPEED = table_int(0, N_SPEEDS - 1, "the start speed");
	SPEEDS_MPS = table_alloc(N_SPEEDS, sizeof(double));
	GAIN_M = table_alloc(N_SPEEDS, sizeof(double));
	for (i = 0; i < N_SPEEDS; i++) { SPEEDS_MPS[i] = table_number(); }
	for (i = 0; i < N_SPEEDS; i++) { GAIN_M[i] = table_number(); }
	for (i = 0; i < CONTINUATION; i++) { ACTION_SPEED[i] = table_int(0, N_SPEEDS - 1, "an action's speed"); }
	N_WINDOWS = table_int(1, 10000000, "windows");
	WINDOWS = table_alloc(N_WINDOWS, sizeof(SoundWindow));
	for (k = 0; k < N_WINDOWS; k++)
	{	w = &WINDOWS[k];
		w->n = table_int(0, 1000, "a window's stretches");
		w->bt = table_number(); w->bx = table_number(); w->et = table_number(); w->ex = table_number();
		w->ev = table_number();
		w->closes = table_int(0, 1, "closes"); w->rear_closes = table_int(0, 1, "rear closes");
		w->s = table_alloc(w->n, sizeof(SoundStretch));
		for (i = 0; i < w->n; i++)
		{	st = &w->s[i];
			st->left = table_int(0, 1, "left"); st->right = table_int(0, 1, "right");
			st->entering = table_int(0, 1, "entering"); st->at_start = table_int(0, 1, "at start");
			st->n = table_int(1, 1000, "a stretch's pieces");
			st->p = table_alloc(st->n, sizeof(SoundPiece));
			for (j = 0; j < st->n; j++)
			{	p = &st->p[j];
				p->t0 = table_number(); p->x0 = table_number();
				table_at_instant(&p->ahead); table_at_instant(&p->oncoming); table_at_instant(&p->behind);
				p->rear = table_int(0, 1, "rear");
				p->t1 = table_number(); p->v0 = table_number(); p->acc = table_number();
	}	}	}
	n = N_SPEEDS * (CONTINUATION + 1) * 2 * 3;
	RELATIVE_ = table_alloc(n, sizeof(short));
	for (i = 0; i < n; i++) { RELATIVE_[i] = (short) table_int(-1, N_WINDOWS - 1, "a shape's window"); }
	N_EARLY = table_int(0, 10000000, "early windows");
	EARLY = table_alloc(N_EARLY, sizeof(SoundEarly));
	for (k = 0; k < N_EARLY; k++)
	{	EARLY[k].lane = table_int(0, 1, "an early window's lane");
		EARLY[k].t = table_int(0, 1000000, "an early window's time");
		EARLY[k].d = table_int(-1000000, 1000000, "an early window's advance");
		EARLY[k].first = table_int(NO_SPEED, N_SPEEDS - 1, "an early window's first speed");
		EARLY[k].last = table_int(NO_SPEED, N_SPEEDS - 1, "an early window's last speed");
		EARLY[k].moved = table_int(0, 2, "an early window's lane moved into");
		EARLY[k].action = table_int(0, CONTINUATION, "an early window's action");
		EARLY[k].window = table_int(0, N_WINDOWS - 1, "an early window's window");
	}
	START_WINDOW[0] = table_int(0, N_WINDOWS - 1, "a start window");
	START_WINDOW[1] = table_int(0, N_WINDOWS - 1, "a start window");
	CUT_ = table_alloc(N_WINDOWS * N_SPEEDS, sizeof(int));
	for (i = 0; i < N_WINDOWS * N_SPEEDS; i++) { CUT_[i] = -1; }
	n = table_int(0, 10000000, "cut windows");
	for (k = 0; k < n; k++)
	{	i = table_int(0, N_WINDOWS - 1, "a cut window's step");
		j = table_int(0, N_SPEEDS - 1, "a cut window's following speed");
		CUT(i, j) = table_int(0, N_WINDOWS - 1, "a cut window");
	}
	if (table_int(TABLE_END, TABLE_END, "its end") != TABLE_END) { sound_bad_table("its end"); }
	while (*table_at == ' ' || *table_at == '\n' || *table_at == '\t' || *table_at == '\r') { table_at++; }
	if (*table_at) { sound_bad_table("more after its end"); }
	table_loaded = strdup(path);  /* none (out of memory): read again by the next run */
}

/* a served verifier's hook (serve.c: SERVE_PREPARE), before it forks a run: the request's table read once, by its
   path (named by the hash of its text), so each run finds it read; a table that will not read is left to the run,
   which reports it and exits 2 */
static void sound_prepare(const char *scenario)
{	const char *bar = strchr(scenario, '|');
	jmp_buf trap;
	if (!bar) { return; }
	bar++;
	while (*bar == ' ') { bar++; }
	if (setjmp(trap)) { table_trap = NULL; return; }
	table_trap = &trap;
	sound_load_table(bar);
	table_trap = NULL;
}
\#define SERVE_PREPARE sound_prepare

/* the scenario: lane nl cells... nr cells... nt ft horizon, each phantom's edge (dx: where its sensor's view ends),
   then 0, or 1 and each vehicle's sensed interval (lo hi, same-direction then oncoming), then 0, or 1 and for each
   vehicle (same-direction then oncoming) 0, or 1 and its interval at the plan's start and its own dynamics there (lo
   hi low high top: spec.sound.vehicles), then the probe: 0, or its code and the sequence's length and its actions'
   codes (a batch: 5, how many, then each one's kind, length and codes), then | and the path of the sound model's
   table; the vehicles as intervals (those, or their cells' extents, widened), then the phantoms */
#define SOUND_VALUES (18 * (ROAD_CELLS + 1) + N_PHANTOMS + MAX_BATCH * (MAX_SEQ + 2) + 18)
static void sound_load(void)
{	char *text = getenv("ENV_NAME"), *end, *bar;
	static double v[SOUND_VALUES];
	int n = 0, at = 0, j, k, lane, cell, measured, speeds;
	double lo, hi;
	if (!text) { fprintf(stderr, "overtake: ENV_NAME is not set\n"); exit(2); }
	bar = strchr(text, '|');
	if (!bar) { sound_malformed("no table: | and its path at the end"); }
	end = bar + 1;
	while (*end == ' ') { end++; }
	sound_load_table(end);
	while (n < SOUND_VALUES)
	{	v[n] = strtod(text, &end);
		if (end == text) { break; }
		n++; text = end;
	}
	if (n < 7) { sound_malformed("too few numbers"); }
	lane = (int) v[at++];
	if (lane != LEFT && lane != RIGHT) { sound_malformed("lane"); }
	n_left = (int) v[at++];
	if (n_left < 0 || n_left > ROAD_CELLS + 1 || at + n_left + 5 > n) { sound_malformed("left-lane count"); }
	if (n_left + N_PHANTOMS > MAX_SAME) { sound_malformed("more same-direction vehicles than the followers hold"); }
	for (j = 0; j < n_left; j++) { left_cells[j] = (int) v[at++]; }
	n_right = (int) v[at++];
	if (n_right < 0 || n_right > ROAD_CELLS + 1 || at + n_right + 4 > n) { sound_malformed("right-lane count"); }
	for (j = 0; j < n_right; j++) { right_cells[j] = (int) v[at++]; }
	n_targets = (int) v[at++];
	first_target = (int) v[at++];
	if (n_targets < 0 || first_target < 0 || first_target + n_targets > n_left
	||  v[at] < 0 || v[at] > MAX_HORIZON) { sound_malformed("targets or horizon"); }
	now.horizon = (int) v[at++];
	now.lane = lane;
	if (at + N_PHANTOMS >= n) { sound_malformed("the phantoms' edges"); }
	for (j = 0; j < N_PHANTOMS; j++)
	{	PHANTOMS[j].dx = v[at++];
		if (!(PHANTOMS[j].dx == PHANTOMS[j].dx) || PHANTOMS[j].dx == 0.0
		||  (PHANTOMS[j].lane == RIGHT && PHANTOMS[j].dx < 0.0)) { sound_malformed("a phantom's edge"); }
	}
	measured = (int) v[at++];
	if ((measured != 0 && measured != 1) || at + (measured ? 2 * (n_left + n_right) : 0) >= n)
	{	sound_malformed("the sensed intervals");
	}
	n_same = 0;
	for (j = 0; j < n_left; j++)
	{	cell = left_cells[j];
		if (cell < 0 || cell > ROAD_CELLS) { sound_malformed("a left-lane cell"); }
		lo = measured ? v[at++] : LEFT_EXTENT[lane][cell][0];
		hi = measured ? v[at++] : LEFT_EXTENT[lane][cell][1];
		if (!(lo <= hi)) { sound_malformed("a left-lane interval"); }
		S_LO[n_same] = lo - START_ERROR_M;
		S_HI[n_same] = hi + START_ERROR_M;
		n_same++;
	}
	n_onc = 0;
	for (j = 0; j < n_right; j++)
	{	cell = right_cells[j];
		if (cell < 0 || cell > ROAD_CELLS) { sound_malformed("a right-lane cell"); }
		lo = measured ? v[at++] : ONCOMING_EXTENT[cell][0];
		hi = measured ? v[at++] : ONCOMING_EXTENT[cell][1];
		if (!(lo <= hi)) { sound_malformed("a right-lane interval"); }
		O_LO[n_onc] = lo - START_ERROR_ONC_M;
		O_HI[n_onc] = hi + START_ERROR_ONC_M;
		n_onc++;
	}
	speeds = (int) v[at++];
	if (speeds != 0 && speeds != 1) { sound_malformed("the measured speeds"); }
	for (j = 0; j < n_same + n_onc; j++)
	{	SoundMotion *m = j < n_same ? &S_MOT[j] : &O_MOT[j - n_same];
		m->measured = 0;
		if (!speeds) { continue; }
		if (at >= n || (v[at] != 0.0 && v[at] != 1.0)) { sound_malformed("a vehicle's measured speed"); }
		if (v[at++] == 0.0) { continue; }
		if (at + 5 > n || !(v[at] <= v[at + 1]) || !(0 <= v[at + 2] && v[at + 2] <= v[at + 3])
		||  !(v[at + 4] > 0) || v[at + 3] == __builtin_inf() || v[at + 4] == __builtin_inf())
		{	sound_malformed("a vehicle's measured speed");
		}
		if (j < n_same) { S_LO[j] = v[at]; S_HI[j] = v[at + 1]; }
		else { O_LO[j - n_same] = v[at]; O_HI[j - n_same] = v[at + 1]; }
		sound_motion(m, v[at + 2], v[at + 3], v[at + 4]);
		at += 5;
	}
	if (at >= n) { sound_malformed("no probe"); }
	SQ_PROBE = (int) v[at++];
	if (SQ_PROBE < 0 || SQ_PROBE > SQ_BATCH) { sound_malformed("the probe"); }
	N_BATCH = 1;
	B_KIND[0] = SQ_PROBE;
	B_LEN[0] = 0;
	if (SQ_PROBE == SQ_BATCH)
	{	if (at >= n || v[at] < 1 || v[at] > MAX_BATCH) { sound_malformed("the batch"); }
		N_BATCH = (int) v[at++];
	}
	now.horizon = SQ_PROBE ? 0 : now.horizon;
	for (k = 0; SQ_PROBE && SQ_PROBE != SQ_START && k < N_BATCH; k++)
	{	if (SQ_PROBE == SQ_BATCH)
		{	if (at >= n || (v[at] != SQ_ESCAPE && v[at] != SQ_WHOLE)) { sound_malformed("a batch's kind"); }
			B_KIND[k] = (int) v[at++];
		}
		if (at >= n || v[at] < 0 || v[at] > MAX_SEQ || at + 1 + (int) v[at] > n) { sound_malformed("the sequence"); }
		B_LEN[k] = (int) v[at++];
		for (j = 0; j < B_LEN[k]; j++)
		{	if (v[at] < 0 || v[at] >= CONTINUATION) { sound_malformed("a sequence's action"); }
			B_SEQ[k][j] = (int) v[at++];
		}
		if (B_LEN[k] > now.horizon) { now.horizon = B_LEN[k]; }  /* may run past the plan's horizon */
	}
	now.seq = SQ_PROBE != 0;
	now.nbatch = N_BATCH;
	if (at != n) { sound_malformed("more numbers than the scenario holds"); }
	held_passing = 0;
	for (j = 0; j < n_same; j++) { if (NO_ACCELERATION && S_MOT[j].measured) { held_passing = 1; } }
	for (j = 0; j < N_PHANTOMS; j++)  /* the unseen stretch from the view's edge outwards */
	{	lo = PHANTOMS[j].dx > 0 ? PHANTOMS[j].dx : -__builtin_inf();
		hi = PHANTOMS[j].dx > 0 ? __builtin_inf() : PHANTOMS[j].dx;
		if (PHANTOMS[j].lane == LEFT) { S_LO[n_same] = lo; S_HI[n_same] = hi; S_MOT[n_same].measured = 0; n_same++; }
		else { O_LO[n_onc] = lo; O_HI[n_onc] = hi; O_MOT[n_onc].measured = 0; n_onc++; }
	}
}
}"""


def _option(action: Action, grid: Grid) -> str:
    """One decision step as one atomic transition: guard, safety test, effect, STEP line, goal."""
    rule = ACTION_RULES[action]
    code = ACTION_ORDER.index(action)
    guard = ["!refused", "steps < horizon"]
    if rule.from_lane is not None:
        guard.append(f"lane == {rule.from_lane.name}")
    if rule.changes_lane:
        guard.append("(seq || lc < MAX_LC)")  # a probed sequence's escape keeps no count of lane changes
    effect = []
    if rule.to_lane is Lane.LEFT:
        effect += ["c_code { sound_take_followers(); }", "out = -1"]
    if rule.to_lane is Lane.RIGHT:  # the passing window starts (spec.sound.SoundRules.after)
        effect.append("c_code { if (held_passing) { now.out = now.t; } }")
    if rule.to_lane is not None:
        effect += [f"lane = {rule.to_lane.name}", "lc++"]
    units = grid.units(action)
    effect += ["steps++", f"t = t + {units}", f"d = d + {units - grid.left_shift(action)}",
               f"c_code {{ sound_speeds({code}); }}", f"moved = {MOVED_CODE[rule.to_lane]}",
               f'c_code {{ sound_show("STEP {action.value}"); now.reached = sound_done(); }}', "assert(!reached)"]
    return (f"  :: d_step {{ {' && '.join(guard)} ->\n"
            f"       c_code {{ sound_ok = sound_step_ok({code}); }};\n"
            f"       if\n"
            f"       :: c_expr {{ sound_ok }} ->\n"
            f"          {'; '.join(effect)}\n"
            f"       :: else -> skip  /* refused: no successor */\n"
            f"       fi }}")


@functools.lru_cache(maxsize=64)
def render(shape: SoundShape) -> str:
    """The sound model's Promela+C model of ``shape``, the scenario injected at run time (rendered once per shape: the
    verifier's cache key hashes it on every search)."""
    rules, goal, grid = shape.rules, shape.goal, shape.grid
    lanes = ", ".join(lane.value for lane in shape.phantoms) or "none"
    what = (f"the sound model (its numbers read from its table at the start), phantoms' lanes {lanes}; "
            f"{rules.kind.value} model, goal {goal.kind.value}, {grid.describe()}")
    parts = [
        f"/* overtake-mc: {what}; rendered from spec/, do not edit */",
        f"#define MAX_LC {rules.max_lane_changes}",
        "#define LEFT 0",
        "#define RIGHT 1",
        f"#define FW {shape.words}",
        _tables(shape),
        "",
        "bit lane; byte lc; byte steps; short t; short d;  /* time units, cells of nominal advance */",
        f"short first = {NO_SPEED}; short last = {NO_SPEED};  /* speed indices */",
        "byte moved;  /* the lane the last action moved into: 0 none, 1 left, 2 right */",
        "short out = -1;  /* when the move into the passing lane the AV is in began, time units (-1: none) */",
        "int fol[FW];  /* followers: bit i of word i / 32 for the same-direction vehicle i */",
        "bool refused; bool reached; byte horizon;  /* the horizon: constant after the start */",
        "bool seq;  /* a sequence is probed (constant after the start) */",
        "short nbatch; short seqid;  /* the sequences probed, and the one this path follows */",
        "",
        _FUNCTIONS.replace("GOAL", _goal(goal)).replace("ENV_NAME", ENV_VAR),
        "",
        "active proctype av() {",
        "  c_code { sound_load(); };",
        "  if  /* a batch: each sequence its own path, chosen in one step */",
        *(f"  :: nbatch > {k} -> seqid = {k}" for k in range(MAX_BATCH)),
        "  fi;",
        "  d_step { c_code { sound_start(); };",
        '           if :: !refused -> c_code { sound_show("INIT"); now.reached = sound_done(); } :: else -> skip fi;',
        "           assert(!reached) }",
        "  do",
        *(_option(action, grid) for action in ACTION_ORDER),
        "  od",
        "}",
    ]
    return "\n".join(parts) + "\n"
