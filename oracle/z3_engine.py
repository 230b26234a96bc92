"""The Z3 engine, registered once: the paper's rules (``oracle.bmc``) and the sound model (``oracle.bmc_sound``, which
builds on the former's kept solvers) behind one entry point, so that neither encoding imports the other's caller."""

from __future__ import annotations

import z3

from oracle import bmc, bmc_commit, bmc_sound
from spec.answers import Limits, SearchResult, Strategy
from spec.engines import Engine, register
from spec.errors import EngineError
from spec.escapes import Semantics
from spec.scenario import Problem


def _solve(problem: Problem, strategy: Strategy, limits: Limits) -> SearchResult:
    """shortest: incremental bounds; optimal: lexicographic tightening. sensible is left to the search engines. A
    scenario with a sound model goes to ``oracle.bmc_sound``; under the commitment semantics its proofs
    (``oracle.bmc_commit``) composed by ``spec.commitment``.
    Z3 refusing a call because the context was interrupted (an interrupt that lands between checks) is an interrupt
    too, never an engine failure."""
    sound = problem.scenario.sound
    solvers = bmc.SOLVERS if sound is None else bmc_sound.SOLVERS
    try:
        if sound is not None and sound.commitment is not None:
            return bmc_commit.solve(problem, strategy, limits)
        if sound is not None and (problem.scenario.left_mps or problem.scenario.right_mps):
            raise EngineError("z3: measured speeds are answered under the commitment semantics only (its whole-plan "
                              "encoding moves every vehicle at its lane's speeds)")
        return solvers[strategy](problem, limits)
    except z3.Z3Exception as err:
        if bmc._cancelled(str(err)):
            raise KeyboardInterrupt("z3: interrupted") from None
        raise


Z3 = register(Engine("z3", tuple(bmc.SOLVERS), _solve,
                     "Z3 bounded model checking: shortest lengths, optimal plans, proofs within the horizon",
                     sound=True, commit=True, measured_speeds=(Semantics.COMMIT,),
                     overtaken_profile=(Semantics.COMMIT,)))
