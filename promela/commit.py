"""Spin's proofs for the commitment semantics (``spec.commitment.Proofs``), each one run of a served verifier.

A sequence known whole (a committed part and its escape, or a whole plan) is probed in the sound model's verifier
(``promela.render.Probe``): its actions are the only ones enabled, each step's window cut where the ramp into the
next starts (the table's cut windows, ``spec.windows.cut_shapes``), and the assertion fails where it ends safe for
ever (with the goal, for a whole plan): a trail means "proved". The prediction is a search of the paper model's
verifier with its first actions restricted to the committable ones. Spin proves no "no plan of any length": its
answer is "no plan within the horizon" where the interpreter's may be "no plan".
"""

from __future__ import annotations

import time
from collections.abc import Container, Sequence

from promela import runner
from promela.render import Probe, Query
from promela.sound import MAX_BATCH
from spec.actions import Action
from spec.answers import Limits, SearchResult, Status, Strategy
from spec.commitment import ProofIncomplete, answer, committable_in_order, paper_problem
from spec.errors import EngineError
from spec.scenario import Problem
from spec.state import State


class Spin:
    """Spin's proofs of one problem, each sequence probed once."""

    def __init__(self, problem: Problem, limits: Limits) -> None:
        self.problem, self.limits, self.started = problem, limits, time.perf_counter()
        self._held: dict[tuple[tuple[Action, ...], bool], bool] = {}

    def _probe(self, probe: Probe, actions: Sequence[Action]) -> SearchResult:
        """One run of the sound verifier within what is left of the answer's time limit."""
        left = self.limits.remaining(self.started, time.perf_counter()).timeout_s
        found = runner.search(self.problem, Strategy.SENSIBLE, left, query=Query(probe=probe, sequence=tuple(actions)))
        if found.status is Status.INCOMPLETE:
            raise ProofIncomplete(f"spin: probing {probe.name.lower()} along "
                                  f"[{', '.join(a.value for a in actions)}]: {found.detail}")
        return found

    def start_violation(self) -> str | None:
        if self._probe(Probe.START, ()).status is Status.PLAN:
            return None
        return "a vehicle's interval at the start (the verifier's start check)"

    def prefetch(self, asked: Sequence[tuple[tuple[Action, ...], bool]]) -> None:
        """Every sequence not yet proved, in runs of at most ``MAX_BATCH`` (``Probe.BATCH``: one path each)."""
        todo = list(dict.fromkeys(q for q in asked if q not in self._held))
        for start in range(0, len(todo), MAX_BATCH):
            part = todo[start:start + MAX_BATCH]
            left = self.limits.remaining(self.started, time.perf_counter()).timeout_s
            batch = tuple((Probe.WHOLE if goal else Probe.ESCAPE, seq) for seq, goal in part)
            found = runner.search(self.problem, Strategy.SENSIBLE, left, query=Query(probe=Probe.BATCH, batch=batch))
            if found.status is Status.INCOMPLETE:
                raise ProofIncomplete(f"spin: probing {len(part)} sequences together: {found.detail}")
            held = found.extra.get("held")
            if found.status is not Status.NO_PLAN_WITHIN_HORIZON or not isinstance(held, list):
                raise EngineError(f"spin: a batch of {len(part)} sequences answered {found.status.value}")
            for k, query in enumerate(part):
                self._held[query] = k in held

    def holds(self, actions: Sequence[Action], goal: bool) -> bool:
        key = (tuple(actions), goal)
        if key not in self._held:
            self._held[key] = self._probe(Probe.WHOLE if goal else Probe.ESCAPE, actions).status is Status.PLAN
        return self._held[key]

    def predict(self, strategy: Strategy, firsts: Container[Action], limits: Limits) -> SearchResult:
        allowed = committable_in_order(self.problem, firsts)
        if not allowed:
            return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), 1, "no first action is committable")
        left = limits.remaining(self.started, time.perf_counter()).timeout_s
        return runner.search(paper_problem(self.problem), strategy, left, query=Query(firsts=allowed))

    def no_plan_beyond(self) -> bool:
        return False

    def why_not(self, action: Action) -> str:
        return "no escape is proved after it (its step and each escape allowed, probed as one sequence)"

    def states(self, actions: Sequence[Action]) -> tuple[State, ...]:
        walked = self._probe(Probe.WALK, actions)
        if walked.status is not Status.PLAN or len(walked.states) != len(actions) + 1:
            raise EngineError(f"spin: the walk along [{', '.join(a.value for a in actions)}] printed "
                              f"{len(walked.states)} states for {len(actions)} actions")
        return walked.states


def solve(problem: Problem, strategy: Strategy, limits: Limits) -> SearchResult:
    """Spin's answer under the commitment semantics (``spec.commitment.answer``)."""
    return answer(problem, strategy, limits, Spin(problem, limits))
