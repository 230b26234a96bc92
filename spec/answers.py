"""What a planner is asked (a strategy, limits) and answers: a plan, no plan (proved, or within the horizon), a start
that already breaks the safety specification, or an incomplete search; the values every engine returns and every
layer above reads."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from spec.actions import Action
from spec.errors import ExitCode
from spec.escapes import Escape
from spec.models import ModelKind
from spec.state import State


class Strategy(enum.Enum):
    """Which plan an engine is asked for."""

    SENSIBLE = "sensible"  # the first plan of the depth-first search in the action order (Spin's default)
    SHORTEST = "shortest"  # a plan of the fewest actions (the first in the action order, for the interpreter)
    OPTIMAL = "optimal"  # the least lexicographic cost (``spec.cost.COST_DOC``)


class Status(enum.Enum):
    """The five answers, never reported one as another."""

    PLAN = "plan"
    NO_PLAN = "no_plan"  # proved: no plan of any length exists (commitments: no committed step is provable)
    NO_PLAN_WITHIN_HORIZON = "no_plan_within_horizon"  # exhaustive up to the horizon
    INCOMPLETE = "incomplete"  # a search limit was hit: nothing is claimed
    #: the sound model's commitment semantics: the snapshot already breaks the safety specification; never a plan,
    #: the answer names the violation and the escape to take (``spec.escapes.unsafe_start_escape``)
    UNSAFE_START = "unsafe_start"

    @property
    def exit_code(self) -> ExitCode:
        """The CLI's exit code: 0 plan, 1 no plan (an unsafe start among them), 3 incomplete."""
        return {Status.PLAN: ExitCode.OK, Status.INCOMPLETE: ExitCode.INCOMPLETE}.get(self, ExitCode.NO)


@dataclass(frozen=True, slots=True)
class Limits:
    """Bounds on one search: past either, the engine answers ``incomplete``."""

    max_states: int = 2_000_000  # stored states (explicit-state searches)
    timeout_s: float | None = None  # wall-clock seconds for the whole pipeline

    def remaining(self, started: float, now: float) -> Limits:
        """The same limits with the time already spent taken off."""
        if self.timeout_s is None:
            return self
        return Limits(self.max_states, max(0.0, self.timeout_s - (now - started)))


@dataclass(frozen=True, slots=True)
class Commit:
    """The parts of an answer under the commitment semantics (``spec.escapes``): the committed actions (a plan's
    ``actions``, what the AV executes until it decides again), the escape proved from where they end (None: they are
    a whole proved plan; from an unsafe start, the escape to take, unproved) and the predicted continuation to the
    goal under nominal motion (no safety claim)."""

    committed: tuple[Action, ...]
    escape: Escape | None
    predicted: tuple[Action, ...] = ()
    escape_proved: bool = True  # False only from an unsafe start: nothing is proved from it

    def to_json(self) -> dict[str, object]:
        """The three parts, each with what is proved of it."""
        escape = self.escape
        return {
            "committed": {"actions": [a.value for a in self.committed], "proved": True},
            "escape": None if escape is None else {"kind": escape.kind.value,
                                                   "actions": [a.value for a in escape.actions],
                                                   "then": "minimal_risk", "proved": self.escape_proved},
            "predicted": {"actions": [a.value for a in self.predicted], "proved": False,
                          "motion": "the paper's rules from the snapshot's cells: every vehicle at the common speed, "
                                    "no phantoms"},
            "whole_plan": escape is None,
        }


@dataclass(frozen=True, slots=True)
class SearchResult:
    """What one search of one model returns."""

    status: Status
    actions: tuple[Action, ...] = ()
    states_explored: int = 0
    detail: str = ""
    states: tuple[State, ...] = ()  # the engine's own states along the plan (initial included), if it reports them
    extra: dict[str, object] = field(default_factory=dict)  # engine facts: versions, cache hits, costs
    commit: Commit | None = None  # under the commitment semantics: the committed part, the escape, the prediction


@dataclass(frozen=True, slots=True)
class Answer:
    """An engine's answer for a scenario, with the states a plan passes through."""

    status: Status
    model: ModelKind | None  # the model whose plan this is (or the last model tried)
    engine: str
    strategy: Strategy
    actions: tuple[Action, ...]
    states: tuple[State, ...]
    states_explored: int
    elapsed_ms: float
    detail: str = ""
    stages: tuple[tuple[ModelKind, Status, str], ...] = field(default=())
    extra: dict[str, object] = field(default_factory=dict)
    commit: Commit | None = None  # under the commitment semantics (``actions`` are the committed ones)

    def to_json(self) -> dict[str, object]:
        """The documented JSON object of ``overtake plan --json``."""
        return {
            "status": self.status.value,
            "model": self.model.value if self.model else None,
            "engine": self.engine,
            "strategy": self.strategy.value,
            "actions": [a.value for a in self.actions],
            "states": [state_to_json(s) for s in self.states],
            "detail": self.detail,
            "stages": [{"model": m.value, "status": st.value, "detail": d} for m, st, d in self.stages],
            **self.extra,
            **({} if self.commit is None else self.commit.to_json()),
            "stats": {"states_explored": self.states_explored, "elapsed_ms": round(self.elapsed_ms, 3)},
        }


def state_to_json(state: State) -> dict[str, object]:
    """A state as JSON: lane, both lanes' cells, lane changes, steps."""
    return {
        "lane": state.lane.value,
        "left_lane": list(state.left_lane),
        "right_lane": list(state.right_lane),
        "lane_changes": state.lane_changes,
        "steps": state.steps,
    }
