"""Z3's proofs for the commitment semantics (``spec.commitment.Proofs``): its own encoding of the sound model and of
the paper's rules.

A sequence known whole is checked by ``oracle.bmc_sound.SoundEncoding.holds``: the encoding's conditions on each
step's window and the continuation, every state known, simplified at the scenario's interval ends. The prediction
is ``oracle.bmc``'s shortest or optimal plan of the paper's rules with its first action one of the committable ones
(at least one action). Z3 proves no "no plan of any length" of the prediction: its answer is "no plan within the
horizon" where the interpreter's may be "no plan".
"""

from __future__ import annotations

from collections.abc import Container, Sequence

from oracle import bmc, bmc_sound
from oracle.bmc_own import Own
from spec.actions import Action
from spec.answers import Limits, SearchResult, Strategy
from spec.commitment import answer, committable_in_order, paper_problem
from spec.errors import EngineError
from spec.scenario import Problem
from spec.sound import SoundState, advance
from spec.state import State

PREDICTORS = {Strategy.SHORTEST: bmc.shortest, Strategy.OPTIMAL: bmc.optimal}


class Z3:
    """Z3's proofs of one problem, each sequence checked once."""

    def __init__(self, problem: Problem, limits: Limits | None = None) -> None:
        self.problem, self.enc = problem, bmc_sound.encoding(problem)
        self.own = Own(problem.scenario)
        self.timeout_s = None if limits is None else limits.timeout_s
        self._held: dict[tuple[tuple[Action, ...], bool], bool] = {}

    def start_violation(self) -> str | None:
        if not self.enc.start_refused(self.problem.scenario, self.own, self.timeout_s):
            return None
        return "a vehicle's interval at the start (the encoding's start conditions)"

    def prefetch(self, asked: Sequence[tuple[tuple[Action, ...], bool]]) -> None:
        """Nothing: each sequence is checked when asked (a simplification, no solver run)."""

    def holds(self, actions: Sequence[Action], goal: bool) -> bool:
        key = (tuple(actions), goal)
        if key not in self._held:
            self._held[key] = self.enc.holds(self.problem.scenario, actions, goal, self.own, self.timeout_s)
        return self._held[key]

    def predict(self, strategy: Strategy, firsts: Container[Action], limits: Limits) -> SearchResult:
        allowed = committable_in_order(self.problem, firsts)
        if strategy not in PREDICTORS:
            raise EngineError(f"z3 answers {', '.join(s.value for s in PREDICTORS)} only")
        return PREDICTORS[strategy](paper_problem(self.problem), limits, allowed)

    def no_plan_beyond(self) -> bool:
        return False

    def why_not(self, action: Action) -> str:
        return "no escape is proved after it (its step and each escape allowed, checked as one sequence)"

    def states(self, actions: Sequence[Action]) -> tuple[State, ...]:
        return display_states(self.problem, actions)


def display_states(problem: Problem, actions: Sequence[Action]) -> tuple[State, ...]:
    """The display states along ``actions`` from the encoding's own arithmetic: each vehicle's cell moved by the time
    elapsed and the AV's nominal advance (``spec.sound.advance``), as ``bmc_sound.Unrolling.decode`` reads them off a
    model."""
    s, grid = problem.scenario, problem.grid
    state = SoundState(s.lane, 0, 0, 0, 0, None, None)
    shown = [State(s.lane, s.left_lane, s.right_lane, 0, 0)]
    for action in actions:
        state = advance(state, action, grid, 0.0)  # the speed moves no cell
        t, d = state.t_units, state.d_cells
        shown.append(State(state.lane, tuple(c + t - d for c in s.left_lane), tuple(c - t - d for c in s.right_lane),
                           state.lane_changes, state.steps))
    return tuple(shown)


def solve(problem: Problem, strategy: Strategy, limits: Limits) -> SearchResult:
    """Z3's answer under the commitment semantics (``spec.commitment.answer``)."""
    return answer(problem, strategy, limits, Z3(problem, limits))
