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

What does not depend on the scenario is compiled in from spec/: the windows of
``spec.windows.sound_table`` (shapes, early windows, start windows, gains, speeds), the required gap
at each instant a condition binds (``SafetySpec.required_gap_m`` of the closing speed this module
forms from the instant's speed, the speed error and the lane's bound), the bounds, the envelope,
``EPS_M``, whether each window's end closes in (``MinimalRisk.closes_in``), the phantoms' lanes and
each cell's extent (``spec.cells``). The C code does the rest itself: the vehicles' intervals
(extents widened by the sensing error, then the phantoms from their edges), their growth over time,
the conditions of ``spec.windows``'s docstring, the followers, the goal and the continuation. The
scenario (AV lane, cells, targets, horizon, the phantoms' edges: where a snapshot's view ended) is
read from ``OVERTAKE_SCENARIO`` when the verifier starts (``promela.render.scenario_values``), so
one compiled verifier serves every scenario of its (sound model less the snapshot's view, model,
goal, grid).

Spin refuses a ``c_expr`` that calls a function (it cannot tell a pure one), so each step's test
stores its answer in the C global ``sound_ok`` and the ``c_expr`` reads it.
"""

from __future__ import annotations

import functools
import hashlib
import math
import re
from dataclasses import dataclass, replace

from spec.actions import ACTION_ORDER, ACTION_RULES, Action
from spec.cells import left_extent_m, oncoming_extent_m
from spec.constants import MAX_HORIZON
from spec.errors import EngineError
from spec.grid import Grid
from spec.lanes import Lane
from spec.models import GoalRule, ModelRules
from spec.scenario import Problem
from spec.sound import EPS_M, Checks, Sound, follower_limit_m, rear_binds
from spec.windows import NO_SPEED, Binding, Instant, SoundTable, Window, sound_table

ENV_VAR = "OVERTAKE_SCENARIO"
LANE_CODE = {Lane.LEFT: 0, Lane.RIGHT: 1}
MOVED_CODE = {None: 0, Lane.LEFT: 1, Lane.RIGHT: 2}
CONTINUATION = len(ACTION_ORDER)  # the action code of the minimal-risk continuation (action None)
WORD_BITS = 32


@dataclass(frozen=True, slots=True)
class SoundShape:
    """What a compiled verifier of the sound model is specialised for: the sound model (bounds, safety, tracking,
    start speed, minimal-risk manoeuvre), the model's rules, its goal, the grid, and the words of the followers'
    bitmask."""

    sound: Sound
    rules: ModelRules
    goal: GoalRule
    grid: Grid
    words: int = 1

    @property
    def profile(self) -> str:
        """The bounds' name, as a file name may hold it."""
        return re.sub(r"[^a-z0-9]+", "_", self.sound.bounds.name.lower()).strip("_") or "bounds"

    @property
    def name(self) -> str:
        """``sound-<profile>-model-goal[-cell]-f<words>-<hash of the sound model>``: file and cache names."""
        cell = "" if self.grid.is_paper else f"-{float(self.grid.cell_m):g}m"
        return (f"sound-{self.profile}-{self.rules.kind.value}-{self.goal.kind.value}{cell}-f{self.words}-"
                f"{hashlib.sha256(self.key_text().encode()).hexdigest()[:8]}")

    def key_text(self) -> str:
        """The sound model in full, for the verifier cache's key (the rendered source holds its numbers too)."""
        return repr(self.sound)

    @property
    def left_phantoms(self) -> int:
        return sum(1 for p in self.sound.bounds.phantom_vehicles() if p.lane is Lane.LEFT)

    @property
    def max_same(self) -> int:
        """The most same-direction vehicles the verifier holds: sensed ones, then the phantoms."""
        return min(self.words * WORD_BITS, self.grid.road_cells + 1 + self.left_phantoms)


def full_words(grid: Grid, sound: Sound) -> int:
    """The followers' words for the most same-direction vehicles a scenario on ``grid`` can have."""
    left_phantoms = sum(1 for p in sound.bounds.phantom_vehicles() if p.lane is Lane.LEFT)
    return -(-(grid.road_cells + 1 + left_phantoms) // WORD_BITS)


def shape_of(problem: Problem) -> SoundShape:
    """The verifier shape that serves ``problem``: one word of followers when its same-direction list fits, else as
    many as a full road needs. The identity check's paper cell rules (``Checks.PAPER_CELLS``) are the interpreter's
    only: an engine error."""
    sound = problem.scenario.sound
    if sound is None:
        raise ValueError("the problem's scenario has no sound model")
    if sound.checks is not Checks.PHYSICAL:
        raise EngineError(f"spin answers the sound model's physical checks only, not {sound.checks.value!r} (the "
                          "identity check is the interpreter's)")
    sound = replace(sound, oncoming_view_m=None)  # the phantoms' edges are read with the scenario: one verifier
    shape = SoundShape(sound, problem.rules, problem.goal, problem.grid, 1)
    if len(problem.scenario.left_lane) + shape.left_phantoms > WORD_BITS:
        shape = SoundShape(sound, problem.rules, problem.goal, problem.grid, full_words(problem.grid, sound))
    return shape


# -- C literals ------------------------------------------------------------------------------------------------
def _f(x: float) -> str:
    """A double exactly as Python holds it (``repr`` round-trips; gcc rounds decimal literals correctly)."""
    if not math.isfinite(x):
        raise ValueError(f"promela: a table number is not finite: {x}")
    text = repr(float(x))
    return text if any(c in text for c in ".en") else f"{text}.0"


def _at(inst: Instant, gap_m: float) -> str:
    return f"{{{_f(inst.t_s)}, {_f(inst.x_m)}, {_f(gap_m)}}}"


def _piece(b: Binding, sound: Sound) -> str:
    """A piece: its start, and each condition's instant with the gap required there at that instant's worst
    closing speed (AHEAD: v + e_v - low; ONCOMING: v + e_v + high_o; behind: high - v + e_v)."""
    s, e_v, same, onc = sound.safety, sound.tracking.speed_mps, sound.bounds.same_mps, sound.bounds.oncoming_mps
    ahead = s.required_gap_m(b.ahead.v_mps + e_v - same.low_mps)
    oncoming = s.required_gap_m(b.oncoming.v_mps + e_v + onc.high_mps)
    behind = s.required_gap_m(same.high_mps - b.behind.v_mps + e_v)
    return (f"{{{_f(b.start.t_s)}, {_f(b.start.x_m)}, {_at(b.ahead, ahead)}, {_at(b.oncoming, oncoming)}, "
            f"{_at(b.behind, behind)}, {int(b.rear)}}}")


def _window(w: Window, sound: Sound, name: str) -> str:
    stretches = []
    for s in w.stretches:
        pieces = ", ".join(_piece(b, sound) for b in s.pieces)
        stretches.append(f"{{{int(s.left)}, {int(s.right)}, {int(s.entering)}, {int(s.at_start)}, {len(s.pieces)}, "
                         f"{{{pieces}}}}}")
    return (f"  /* {name} */\n  {{{len(w.stretches)}, {{{', '.join(stretches)}}}, {_f(w.boundary.t_s)}, "
            f"{_f(w.boundary.x_m)}, {_f(w.end.t_s)}, {_f(w.end.x_m)}, "
            f"{int(sound.minimal_risk.closes_in(w.end.v_mps, sound.bounds.same_mps.low_mps))}, "
            f"{int(rear_binds(sound.bounds, w.end.v_mps))}}}")


def _action_code(action: Action | None) -> int:
    return CONTINUATION if action is None else ACTION_ORDER.index(action)


def _action_name(action: Action | None) -> str:
    return "continuation" if action is None else action.value


def _tables(shape: SoundShape, table: SoundTable) -> str:
    """Every scenario-independent number, as C constants and static arrays."""
    sound, grid = shape.sound, shape.grid
    b, s, tr = sound.bounds, sound.safety, sound.tracking
    windows: list[str] = []
    relative = [[[[-1] * 3 for _ in Lane] for _ in range(CONTINUATION + 1)] for _ in table.speeds_mps]
    for (before, action, lane, moved), w in sorted(table.relative.items(), key=lambda kv: (
            kv[0][0], _action_code(kv[0][1]), LANE_CODE[kv[0][2]], MOVED_CODE[kv[0][3]])):
        relative[before][_action_code(action)][LANE_CODE[lane]][MOVED_CODE[moved]] = len(windows)
        windows.append(_window(w, sound, f"shape: before speed {before}, {_action_name(action)}, {lane.value} lane, "
                                         f"moved {moved.value if moved else 'none'}"))
    early = []
    for (lane, t, d, first, last, moved, action), w in sorted(table.early.items(), key=lambda kv: (
            LANE_CODE[kv[0][0]], *kv[0][1:5], MOVED_CODE[kv[0][5]], _action_code(kv[0][6]))):
        early.append(f"  {{{LANE_CODE[lane]}, {t}, {d}, {first}, {last}, {MOVED_CODE[moved]}, {_action_code(action)}, "
                     f"{len(windows)}}}")
        windows.append(_window(w, sound, f"early: {lane.value} lane, t {t}, d {d}, first {first}, last {last}, "
                                         f"moved {moved.value if moved else 'none'}, {_action_name(action)}"))
    start = []
    for lane in Lane:
        start.append(str(len(windows)))
        windows.append(_window(table.start[lane], sound, f"start in the {lane.value} lane"))
    rel_rows = ",\n".join(
        "  {" + ", ".join("{" + ", ".join("{" + ", ".join(map(str, m)) + "}" for m in by_lane) + "}"
                          for by_lane in by_action) + "}" for by_action in relative)
    phantoms = [f"{{{LANE_CODE[p.lane]}, 0.0}}" for p in b.phantom_vehicles()] or ["{0, 0.0}"]
    left_ext = ",\n".join(
        "  {" + ", ".join(f"{{{_f(lo)}, {_f(hi)}}}" for lo, hi in (left_extent_m(c, lane, grid)
                                                                 for c in range(grid.road_cells + 1))) + "}"
        for lane in Lane)
    onc_ext = ", ".join(f"{{{_f(lo)}, {_f(hi)}}}" for lo, hi in (oncoming_extent_m(c, grid)
                                                                for c in range(grid.road_cells + 1)))
    max_stretches = max(len(w.stretches) for w in (*table.relative.values(), *table.early.values(),
                                                   *table.start.values()))
    max_pieces = max(len(st.pieces) for w in (*table.relative.values(), *table.early.values(),
                                              *table.start.values()) for st in w.stretches)
    action_speed = ", ".join(str(table.action_speed[a]) for a in ACTION_ORDER)
    into_left = ", ".join(str(int(ACTION_RULES[a].to_lane is Lane.LEFT)) for a in ACTION_ORDER)
    return "\n".join([
        f"#define N_SPEEDS {len(table.speeds_mps)}",
        f"#define N_WINDOWS {len(windows)}",
        f"#define N_EARLY {len(early)}",
        f"#define N_PHANTOMS {len(b.phantom_vehicles())}",
        f"#define MAX_STRETCHES {max_stretches}",
        f"#define MAX_PIECES {max_pieces}",
        f"#define ROAD_CELLS {grid.road_cells}",
        f"#define MAX_SAME {shape.max_same}",
        f"#define MAX_ONC {grid.road_cells + 1 + sum(1 for p in b.phantom_vehicles() if p.lane is Lane.RIGHT)}",
        f"#define MAX_HORIZON {MAX_HORIZON}",
        f"#define CONTINUATION {CONTINUATION}",
        "c_decl {",
        "typedef struct { double t, x, gap; } SoundAt;  /* an instant of the reference, the gap required there */",
        "typedef struct { double t0, x0; SoundAt ahead, oncoming, behind; int rear; } SoundPiece;",
        "typedef struct { int left, right, entering, at_start, n; SoundPiece p[MAX_PIECES]; } SoundStretch;",
        "typedef struct { int n; SoundStretch s[MAX_STRETCHES]; double bt, bx, et, ex; int closes, rear_closes; }"
        " SoundWindow;",
        "typedef struct { int lane, t, d, first, last, moved, action, window; } SoundEarly;",
        "typedef struct { int lane; double dx; } SoundPhantom;  /* dx: read with the scenario (its view) */",
        f"static const double UNIT_S = {_f(table.unit_s)}, CELL_M = {_f(table.cell_m)};",
        f"static const double E_X = {_f(tr.position_m)}, E_V = {_f(tr.speed_mps)}, LEN = {_f(s.vehicle_length_m)};",
        f"static const double EPS_M = {_f(EPS_M)};",
        f"static const double FOLLOWER_M = {_f(follower_limit_m(0.0, s, tr))};  /* spec.sound.follower_limit_m */",
        f"static const double SAME_LOW = {_f(b.same_mps.low_mps)}, SAME_HIGH = {_f(b.same_mps.high_mps)};",
        f"static const double ONC_LOW = {_f(b.oncoming_mps.low_mps)}, ONC_HIGH = {_f(b.oncoming_mps.high_mps)};",
        f"static const double START_ERROR_M = {_f(sound.start_error_m)};  /* sensing error + age */",
        f"static const double SPEEDS_MPS[N_SPEEDS] = {{{', '.join(map(_f, table.speeds_mps))}}};  /* for reading */",
        f"static const double GAIN_M[N_SPEEDS] = {{{', '.join(map(_f, table.gain_m))}}};",
        f"static const int ACTION_SPEED[CONTINUATION] = {{{action_speed}}};",
        f"static const int INTO_LEFT[CONTINUATION] = {{{into_left}}};",
        f"static const int START_SPEED = {table.start_speed};",
        "static const SoundWindow WINDOWS[N_WINDOWS] = {",
        ",\n".join(windows),
        "};",
        "/* the shapes: by speed before the boundary, action (CONTINUATION: none), lane, moved */",
        "static const short RELATIVE[N_SPEEDS][CONTINUATION + 1][2][3] = {",
        rel_rows,
        "};",
        "/* lane, t, d, first, last, moved, action, window */",
        "static const SoundEarly EARLY[N_EARLY + 1] = {",
        ",\n".join([*early, "  {-1, -1, -1, -1, -1, -1, -1, -1}"]),
        "};",
        f"static const int START_WINDOW[2] = {{{', '.join(start)}}};",
        f"static SoundPhantom PHANTOMS[N_PHANTOMS + 1] = {{{', '.join(phantoms)}}};",
        "/* where a vehicle in a cell can be, metres ahead of the AV: same direction (by the AV lane), oncoming */",
        "static const double LEFT_EXTENT[2][ROAD_CELLS + 1][2] = {",
        left_ext,
        "};",
        f"static const double ONCOMING_EXTENT[ROAD_CELLS + 1][2] = {{{onc_ext}}};",
        "/* the scenario, set once when the verifier starts (sound_load) */",
        "static double S_LO[MAX_SAME], S_HI[MAX_SAME], O_LO[MAX_ONC], O_HI[MAX_ONC];",
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
                     "\t\tif (S_HI[i] + SAME_HIGH * t > x - E_X - LEN) return 0;")
    if goal.nearest_target_m is not None:
        lines.append("\tif (n_targets == 0) return 0;\n"
                     "\ti = first_target;\n"
                     "\tif (S_LO[i] + SAME_LOW * t - (x + E_X) - LEN < 0\n"
                     f"\t||  S_HI[i] + SAME_HIGH * t - (x - E_X) - LEN > {_f(float(goal.nearest_target_m))}) return 0;")
    if goal.oncoming_passed:
        lines.append("\tfor (i = 0; i < n_right; i++) if (!sound_passed(i, x, t)) return 0;  /* sensed ones only */")
    return "\n".join(lines)


_FUNCTIONS = r"""c_code {
static int sound_follows(const unsigned *fol, int i) { return (fol[i / 32] >> (i % 32)) & 1u; }

/* a same-direction vehicle clear ahead of the AV at (x, t) for every position: held to AHEAD */
static int sound_held_ahead(int i, double x, double t) { return S_LO[i] + SAME_LOW * t - LEN >= x + E_X; }

/* an oncoming vehicle certainly past the AV at (x, t) */
static int sound_passed(int j, double x, double t) { return O_HI[j] - ONC_LOW * t + LEN <= x - E_X - EPS_M; }

static int sound_ahead_refused(int i, const SoundAt *a, double dt, double dx)
{	return S_LO[i] + SAME_LOW * (a->t + dt) < a->x + dx + E_X + LEN + a->gap + EPS_M;
}

static int sound_oncoming_refused(int j, const SoundAt *a, double dt, double dx)
{	return O_LO[j] - ONC_HIGH * (a->t + dt) < a->x + dx + E_X + LEN + a->gap + EPS_M;
}

static int sound_behind_clear(int i, const SoundAt *a, double dt, double dx)
{	return S_HI[i] + SAME_HIGH * (a->t + dt) <= a->x + dx - E_X - LEN - a->gap - EPS_M;
}

/* a stretch of one occupancy, moved by (dt, dx): whether some vehicle breaks its condition */
static int sound_stretch_refused(const SoundStretch *s, double dt, double dx, const unsigned *fol)
{	int i, k, ahead, behind;
	const SoundPiece *p;
	if (s->left && s->entering)
	{	for (i = 0; i < n_same; i++)  /* each one certainly ahead at every piece, or certainly behind */
		{	ahead = 1; behind = 1;
			for (k = 0; k < s->n; k++)
			{	p = &s->p[k];
				if (sound_ahead_refused(i, &p->ahead, dt, dx)) { ahead = 0; }
				if (!sound_behind_clear(i, &p->behind, dt, dx)) { behind = 0; }
			}
			if (s->at_start)  /* already in the lane: one that cannot be clear ahead follows */
			{	behind = S_HI[i] <= s->p[0].x0 + dx + FOLLOWER_M - EPS_M;
			}
			if (!ahead && !behind) { return 1; }
		}
	} else if (s->left)
	{	for (k = 0; k < s->n; k++)
		{	p = &s->p[k];
			for (i = 0; i < n_same; i++)
			{	if (!sound_follows(fol, i) && sound_held_ahead(i, p->x0 + dx, p->t0 + dt)
				&&  sound_ahead_refused(i, &p->ahead, dt, dx)) { return 1; }
				if (p->rear && sound_follows(fol, i)  /* BEHIND: a follower that keeps its speed */
				&&  !sound_behind_clear(i, &p->behind, dt, dx)) { return 1; }
		}	}
	}
	if (s->right)
	{	for (k = 0; k < s->n; k++)
		{	p = &s->p[k];
			for (i = 0; i < n_onc; i++)
			{	if (!sound_passed(i, p->x0 + dx, p->t0 + dt)
				&&  sound_oncoming_refused(i, &p->oncoming, dt, dx)) { return 1; }
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
	k = RELATIVE[before][action][now.lane][now.moved];
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
{	double dt, dx;
	int i, k;
	const SoundWindow *w = sound_window(action, &dt, &dx);
	for (k = 0; k < FW; k++) { step_fol[k] = (unsigned) now.fol[k]; }
	if (INTO_LEFT[action])  /* those not held ahead at the boundary follow the AV from now on */
	{	for (k = 0; k < FW; k++) { step_fol[k] = 0; }
		for (i = 0; i < n_same; i++)
		{	if (!sound_held_ahead(i, w->bx + dx, w->bt + dt)) { step_fol[i / 32] |= 1u << (i % 32); }
	}	}
	for (k = 0; k < w->n; k++)
	{	if (sound_stretch_refused(&w->s[k], dt, dx, step_fol)) { return 0; }
	}
	return 1;
}

static void sound_take_followers(void)
{	int k;
	for (k = 0; k < FW; k++) { now.fol[k] = (int) step_fol[k]; }
}

/* whether a plan may end here: the goal holds for every position, and the minimal-risk manoeuvre is safe for ever */
static int sound_done(void)
{	double dt, dx, x, t;
	int i, k;
	const SoundWindow *w = sound_window(CONTINUATION, &dt, &dx);
	x = w->bx + dx;
	t = w->bt + dt;
GOAL
	for (k = 0; k < w->n; k++)
	{	if (sound_stretch_refused(&w->s[k], dt, dx, (const unsigned *) now.fol)) { return 0; }
	}
	x = w->ex + dx;
	t = w->et + dt;
	if (now.lane == RIGHT)
	{	for (i = 0; i < n_onc; i++) { if (!sound_passed(i, x, t)) { return 0; } }
	} else
	{	for (i = 0; i < n_same; i++)
		{	if (w->closes && !sound_follows((const unsigned *) now.fol, i) && sound_held_ahead(i, x, t)) { return 0; }
			if (w->rear_closes && sound_follows((const unsigned *) now.fol, i)) { return 0; }
	}	}
	return 1;
}

/* the start, an instant: refused or not; those not held ahead there follow the AV */
static void sound_start(void)
{	const SoundWindow *w = &WINDOWS[START_WINDOW[now.lane]];
	unsigned none[FW];
	int i, k;
	for (k = 0; k < FW; k++) { none[k] = 0; now.fol[k] = 0; }
	for (i = 0; i < n_same; i++)
	{	if (!sound_held_ahead(i, w->bx, w->bt)) { now.fol[i / 32] |= (int) (1u << (i % 32)); }
	}
	now.refused = 0;
	for (k = 0; k < w->n; k++)
	{	if (sound_stretch_refused(&w->s[k], 0.0, 0.0, none)) { now.refused = 1; }
	}
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

/* the scenario: lane nl cells... nr cells... nt ft horizon, each phantom's edge (dx: where its sensor's view ends),
   then 0, or 1 and each vehicle's sensed interval (lo hi, same-direction then oncoming); the vehicles as intervals
   (those, or their cells' extents), then the phantoms */
static void sound_load(void)
{	char *text = getenv("ENV_NAME"), *end;
	double v[6 * (ROAD_CELLS + 1) + N_PHANTOMS + 16];
	int n = 0, at = 0, j, lane, cell, measured;
	double lo, hi;
	if (!text) { fprintf(stderr, "overtake: ENV_NAME is not set\n"); exit(2); }
	while (n < 6 * (ROAD_CELLS + 1) + N_PHANTOMS + 16)
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
	if ((measured != 0 && measured != 1) || at + (measured ? 2 * (n_left + n_right) : 0) != n)
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
		O_LO[n_onc] = lo - START_ERROR_M;
		O_HI[n_onc] = hi + START_ERROR_M;
		n_onc++;
	}
	for (j = 0; j < N_PHANTOMS; j++)  /* the unseen stretch from the view's edge outwards */
	{	lo = PHANTOMS[j].dx > 0 ? PHANTOMS[j].dx : -__builtin_inf();
		hi = PHANTOMS[j].dx > 0 ? __builtin_inf() : PHANTOMS[j].dx;
		if (PHANTOMS[j].lane == LEFT) { S_LO[n_same] = lo; S_HI[n_same] = hi; n_same++; }
		else { O_LO[n_onc] = lo; O_HI[n_onc] = hi; n_onc++; }
	}
}
}"""


def _option(action: Action, grid: Grid, table: SoundTable) -> str:
    """One decision step as one atomic transition: guard, safety test, effect, STEP line, goal."""
    rule = ACTION_RULES[action]
    code = ACTION_ORDER.index(action)
    guard = ["!refused", "steps < horizon"]
    if rule.from_lane is not None:
        guard.append(f"lane == {rule.from_lane.name}")
    if rule.changes_lane:
        guard.append("lc < MAX_LC")
    effect = []
    if rule.to_lane is Lane.LEFT:
        effect.append("c_code { sound_take_followers(); }")
    if rule.to_lane is not None:
        effect += [f"lane = {rule.to_lane.name}", "lc++"]
    speed = table.action_speed[action]
    units = grid.units(action)
    effect += ["steps++", f"t = t + {units}", f"d = d + {units - grid.left_shift(action)}",
               f"first = (first == {NO_SPEED} -> {speed} : first)", f"last = {speed}",
               f"moved = {MOVED_CODE[rule.to_lane]}",
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
    table = sound_table(shape.sound, shape.grid)
    rules, goal, grid = shape.rules, shape.goal, shape.grid
    start = "" if shape.sound.start_mps is None else f", measured start speed {shape.sound.start_mps:g} m/s"
    what = f"{shape.sound.describe()}{start}; {rules.kind.value} model, goal {goal.kind.value}, {grid.describe()}"
    parts = [
        f"/* overtake-mc: {what}; rendered from spec/, do not edit */",
        f"#define MAX_LC {rules.max_lane_changes}",
        "#define LEFT 0",
        "#define RIGHT 1",
        f"#define FW {shape.words}",
        _tables(shape, table),
        "",
        "bit lane; byte lc; byte steps; short t; short d;  /* time units, cells of nominal advance */",
        f"short first = {NO_SPEED}; short last = {NO_SPEED};  /* speed indices */",
        "byte moved;  /* the lane the last action moved into: 0 none, 1 left, 2 right */",
        "int fol[FW];  /* followers: bit i of word i / 32 for the same-direction vehicle i */",
        "bool refused; bool reached; byte horizon;  /* the horizon: constant after the start */",
        "",
        _FUNCTIONS.replace("GOAL", _goal(goal)).replace("ENV_NAME", ENV_VAR),
        "",
        "active proctype av() {",
        "  c_code { sound_load(); };",
        "  d_step { c_code { sound_start(); };",
        '           if :: !refused -> c_code { sound_show("INIT"); now.reached = sound_done(); } :: else -> skip fi;',
        "           assert(!reached) }",
        "  do",
        *(_option(action, grid, table) for action in ACTION_ORDER),
        "  od",
        "}",
    ]
    return "\n".join(parts) + "\n"
