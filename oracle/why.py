"""Why is there no plan under the sound model? The vehicles that block every plan, and the assumption to blame.

Z3 refuses the sound model, so every question here goes to the interpreter (``oracle.planner.plan``, strategy
shortest):

- **vehicles**: a minimal set of sensed vehicles and phantoms (the unseen stretch beyond each sensor's view,
  ``spec.sound.Sound.phantoms``) whose presence leaves no plan, by deletion: start from all of them and drop each
  whose removal still leaves no plan, sensed vehicles first (so a phantom that blocks on its own is named rather
  than the sensed vehicle it hides). Checked like the Z3 explanation: the set alone has no plan, and removing any
  one of them gives one (a removal that does not is dropped and the check repeated, so the set is minimal).
- **assumptions** (the bound as the reason): each one narrowed to the paper's world alone, everything else as
  stated: no phantoms, the ``paper`` profile's same-direction or oncoming speeds, exact sensing, the AV exactly on
  its reference (``spec.envelope.EXACT_AV``); then all of them at once; and the least set of narrowings found that
  gives a plan (a single one if any does, else deletion from all of them).

The sound model's answers without a plan are told apart: ``no_plan`` for a start that already breaks the
specification (its violation is named) or when every path is refused before the horizon (``oracle.sound.shortest``'s
proof), ``no_plan_within_horizon`` otherwise.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable
from dataclasses import dataclass, fields, replace

from oracle import sound as sound_model
from oracle.explain import Vehicle, keep_only, vehicle_name
from oracle.planner import plan
from spec.answers import Answer, Status, Strategy
from spec.assumptions import Bounds, Phantom, profile
from spec.constants import MAX_HORIZON
from spec.envelope import EXACT_AV
from spec.errors import EngineError
from spec.grid import STANDARD_CELLS_M, Grid
from spec.lanes import Lane
from spec.models import models_for
from spec.scenario import Scenario, problem_for, refined
from spec.sound import Sound, Violation
from spec.state import Collision

#: A vehicle explain may blame: a sensed one (its lane and index, as ``oracle.explain`` names it) or a phantom.
Suspect = Vehicle | Phantom

#: The world the assumptions are narrowed to: the paper's (every vehicle at the common speed, exact sensing).
PAPER = profile("paper")


class Assumption(enum.Enum):
    """An assumption of the sound model that explain narrows to the paper's world."""

    PHANTOMS = "phantoms"  # vehicles beyond the sensors' ranges -> none
    SAME_SPEEDS = "same_mps"  # same-direction speed interval -> the paper profile's
    ONCOMING_SPEEDS = "oncoming_mps"  # oncoming speed interval -> the paper profile's
    SENSING_ERROR = "sensing_error_m"  # sensing error -> 0 m
    ENVELOPE = "envelope"  # the AV's tracking error and sideways move -> exactly on its reference, instant

    @property
    def label(self) -> str:
        """What the assumption is, in words."""
        return {Assumption.PHANTOMS: "phantoms", Assumption.SAME_SPEEDS: "same-direction speeds",
                Assumption.ONCOMING_SPEEDS: "oncoming speeds", Assumption.SENSING_ERROR: "sensing error",
                Assumption.ENVELOPE: "the AV's envelope"}[self]


def narrow(sound: Sound, assumption: Assumption) -> Sound:
    """``sound`` with ``assumption`` narrowed to the paper's world and everything else unchanged."""
    b = sound.bounds
    if assumption is Assumption.PHANTOMS:
        return replace(sound, bounds=replace(b, phantoms=False))
    if assumption is Assumption.SAME_SPEEDS:
        return replace(sound, bounds=replace(b, same_mps=PAPER.same_mps))
    if assumption is Assumption.ONCOMING_SPEEDS:
        return replace(sound, bounds=replace(b, oncoming_mps=PAPER.oncoming_mps))
    if assumption is Assumption.SENSING_ERROR:
        return replace(sound, bounds=replace(b, sensing_error_m=0.0))
    return replace(sound, tracking=EXACT_AV)


def stated(sound: Sound, assumption: Assumption) -> str:
    """The value of ``assumption`` in ``sound``, as text with its units."""
    b, t = sound.bounds, sound.tracking
    speeds = {Assumption.SAME_SPEEDS: b.same_mps, Assumption.ONCOMING_SPEEDS: b.oncoming_mps}.get(assumption)
    if speeds is not None:
        return f"{speeds.low_mps:g}..{speeds.high_mps:g} m/s"
    if assumption is Assumption.PHANTOMS:
        return "on" if b.phantoms else "off"
    if assumption is Assumption.SENSING_ERROR:
        return f"{b.sensing_error_m:g} m"
    if t == EXACT_AV:
        return "none (exactly on its reference, lane changes instant)"
    return f"+-{t.position_m:g} m, +-{t.speed_mps:g} m/s, sideways move {t.lateral_s:g} s"


def narrowable(sound: Sound) -> tuple[Assumption, ...]:
    """The assumptions of ``sound`` wider than the paper's world (narrowing the others changes nothing)."""
    return tuple(a for a in Assumption if narrow(sound, a) != sound)


@dataclass(frozen=True, slots=True)
class Narrowed:
    """Some assumptions narrowed to the paper's world, everything else as stated, and the pipeline's answer then."""

    assumptions: tuple[Assumption, ...]
    answer: Answer

    @property
    def has_plan(self) -> bool:
        return self.answer.status is Status.PLAN


@dataclass(frozen=True, slots=True)
class Widened:
    """A parameter of the question, not an assumption (the horizon, the cell size), changed alone, and the answer."""

    what: str  # "horizon", "cell size"
    stated: str
    changed: str
    answer: Answer

    @property
    def has_plan(self) -> bool:
        return self.answer.status is Status.PLAN


@dataclass(frozen=True, slots=True)
class SoundExplanation:
    """Why a scenario of the sound model has no plan: which answer, the start's violation, the blocking vehicles
    with the plan each removal allows, and what narrowing the assumptions does."""

    scenario: Scenario
    answer: Answer  # the pipeline's answer on the scenario as given
    violation: Violation | Collision | None  # an unsafe start (``no_plan``): what breaks the specification there
    blocking: tuple[Suspect, ...]  # a minimal set of vehicles and phantoms that alone leave no plan
    reduced: Scenario | None  # the scenario with only those
    removals: tuple[tuple[Suspect, Answer], ...]  # each removed from the reduced scenario: the plan it allows
    narrowings: tuple[Narrowed, ...]  # each assumption wider than the paper's world narrowed alone
    everything: Narrowed | None  # all of them narrowed at once (None: none is wider than the paper's world)
    enough: Narrowed | None  # the least set of narrowings found that gives a plan (None: not even all of them)
    parameters: tuple[Widened, ...] = ()  # the horizon and the cell size, each changed alone

    @property
    def status(self) -> Status:
        return self.answer.status

    @property
    def has_plan(self) -> bool:
        return self.answer.status is Status.PLAN

    def name(self, suspect: Suspect) -> str:
        """A vehicle as people read it: a sensed one by lane, index, role and cell; a phantom by lane and place."""
        return name(self.scenario, suspect)


def name(scenario: Scenario, suspect: Suspect) -> str:
    """``suspect`` of ``scenario`` as people read it (sensed vehicles as ``oracle.explain`` names them; a phantom by
    lane, place and the speeds its lane's bounds let it come at)."""
    if isinstance(suspect, Phantom):
        kind = "oncoming" if suspect.lane is Lane.RIGHT else "same-direction"
        bound = None if scenario.sound is None else scenario.sound.bounds.speeds(suspect.lane)
        speeds = "" if bound is None else f", {bound.low_mps:g}..{bound.high_mps:g} m/s"
        return f"the {kind} phantom at {suspect.dx_m:+g} m ({suspect.why}{speeds})"
    return vehicle_name(scenario, suspect)


def suspects(scenario: Scenario) -> tuple[Suspect, ...]:
    """Every vehicle of ``scenario`` explain may blame: the sensed ones (left lane, then right), then the phantoms."""
    sensed: list[Suspect] = [(Lane.LEFT, i) for i in range(len(scenario.left_lane))]
    sensed += [(Lane.RIGHT, i) for i in range(len(scenario.right_lane))]
    return (*sensed, *(scenario.sound.phantoms() if scenario.sound is not None else ()))


@dataclass(frozen=True, slots=True)
class _SomePhantoms(Bounds):
    """Bounds with only some of their phantoms (``kept``, by lane and side: the oncoming one's edge moves with the
    snapshot's view): how explain removes one phantom and keeps the others."""

    kept: frozenset[tuple[Lane, bool]] = frozenset()

    def phantom_vehicles(self, oncoming_view_m: float | None = None) -> tuple[Phantom, ...]:
        return tuple(p for p in Bounds.phantom_vehicles(self, oncoming_view_m) if (p.lane, p.dx_m > 0) in self.kept)


def keep_suspects(scenario: Scenario, keep: Iterable[Suspect]) -> Scenario:
    """``scenario`` with only the sensed vehicles and phantoms in ``keep`` (its assumptions otherwise unchanged)."""
    keep = set(keep)
    reduced = keep_only(scenario, {s for s in keep if not isinstance(s, Phantom)})
    if scenario.sound is None:
        return reduced
    bounds = scenario.sound.bounds
    kept = frozenset((p.lane, p.dx_m > 0) for p in scenario.sound.phantoms() if p in keep)
    if len(kept) == len(scenario.sound.phantoms()):
        return reduced
    some = _SomePhantoms(**{f.name: getattr(bounds, f.name) for f in fields(Bounds)}, kept=kept)
    return replace(reduced, sound=replace(scenario.sound, bounds=some))


def start_violation(scenario: Scenario) -> Violation | Collision | None:
    """What breaks the specification at the start of ``scenario`` (sound model), or None: a safe start (a collision
    only where the sound model's code path checks the paper's cells)."""
    if scenario.sound is None:
        raise ValueError("start_violation: the scenario has no sound model")
    problem = problem_for(scenario, models_for(scenario.model)[0])
    return sound_model.rules_for(problem).start_violation(sound_model.start(problem))


def _ask(scenario: Scenario) -> Answer:
    """The interpreter's answer; a search that hits its limit decides nothing, so explain stops there."""
    answer = plan(scenario, Strategy.SHORTEST)
    if answer.status is Status.INCOMPLETE:
        raise EngineError(f"explain: a search hit its limit ({answer.detail}): nothing is explained")
    return answer


def explain_sound(scenario: Scenario) -> SoundExplanation:
    """Explain a scenario of the sound model without a plan; one with a plan (or a search that hit its limit) is
    reported as such, with nothing else."""
    if scenario.sound is None:
        raise ValueError("explain_sound: the scenario has no sound model (oracle.explain explains the paper's)")
    answer = plan(scenario, Strategy.SHORTEST)
    if answer.status in (Status.PLAN, Status.INCOMPLETE):
        return SoundExplanation(scenario, answer, None, (), None, (), (), None, None)
    violation = start_violation(scenario) if answer.status in (Status.NO_PLAN, Status.UNSAFE_START) else None
    blocking, removals = _blocking(scenario)
    narrowings, everything, enough = _assumptions(scenario)
    reduced = keep_suspects(scenario, blocking)
    return SoundExplanation(scenario, answer, violation, blocking, reduced, removals, narrowings, everything, enough,
                            _parameters(scenario) if violation is None else ())


def _parameters(scenario: Scenario) -> tuple[Widened, ...]:
    """The horizon (to the longest a scenario takes) and the cell size (the finest standard one that divides the
    scenario's, every vehicle's centre where it was: each known more narrowly), each changed alone. A scenario whose
    vehicles were measured (``left_m``, ``right_m``) is not bounded by its cells: no cell size is tried."""
    out = []
    if scenario.horizon < MAX_HORIZON:
        out.append(Widened("horizon", f"{scenario.horizon} actions", f"{MAX_HORIZON} actions",
                           _ask(replace(scenario, horizon=MAX_HORIZON))))
    if scenario.left_m is None and scenario.right_m is None:
        finer = [Grid(c) for c in STANDARD_CELLS_M
                 if Grid(c).cell_m < scenario.grid.cell_m and (scenario.grid.cell_m / Grid(c).cell_m).denominator == 1]
        if finer:
            grid = min(finer, key=lambda g: g.cell_m)
            out.append(Widened("cell size", f"{float(scenario.grid.cell_m):g} m", f"{float(grid.cell_m):g} m",
                               _ask(replace(refined(scenario, grid), sound=scenario.sound))))
    return tuple(out)


def _blocking(scenario: Scenario) -> tuple[tuple[Suspect, ...], tuple[tuple[Suspect, Answer], ...]]:
    """A minimal set of suspects that alone leave no plan, and the plan each one's removal from it allows."""
    blocking = list(suspects(scenario))
    for suspect in list(blocking):  # deletion: drop every suspect not needed to leave no plan
        rest = [s for s in blocking if s != suspect]
        if _ask(keep_suspects(scenario, rest)).status is not Status.PLAN:
            blocking = rest
    while True:  # the check: each removal from the final set gives a plan (else drop it and check again)
        removals = []
        for suspect in blocking:
            answer = _ask(keep_suspects(scenario, [s for s in blocking if s != suspect]))
            if answer.status is not Status.PLAN:
                blocking.remove(suspect)
                break
            removals.append((suspect, answer))
        else:
            return tuple(blocking), tuple(removals)


def _assumptions(scenario: Scenario) -> tuple[tuple[Narrowed, ...], Narrowed | None, Narrowed | None]:
    """Each assumption narrowed alone, all of them at once, and the least set found that gives a plan."""
    base = scenario.sound
    assert base is not None
    asked: dict[frozenset[Assumption], Answer] = {}

    def ask(assumptions: Iterable[Assumption]) -> Narrowed:
        chosen = tuple(a for a in Assumption if a in set(assumptions))
        key = frozenset(chosen)
        if key not in asked:
            sound = base
            for a in chosen:
                sound = narrow(sound, a)
            asked[key] = _ask(replace(scenario, sound=sound))
        return Narrowed(chosen, asked[key])

    wider = narrowable(base)
    if not wider:
        return (), None, None
    singles = tuple(ask([a]) for a in wider)
    everything = ask(wider)
    enough = next((n for n in singles if n.has_plan), None)
    if enough is None and everything.has_plan:
        enough = everything
        for a in wider:  # deletion: restore every assumption not needed for the plan
            rest = [x for x in enough.assumptions if x is not a]
            if len(rest) < len(enough.assumptions) and rest and (trial := ask(rest)).has_plan:
                enough = trial
    return singles, everything, enough
