"""Every conformance property catches the lies it exists for: a stub engine tells each lie
(``ci.conformance.lies``), the property fails on it and holds on the honest engines; a property registered without
its lies fails here."""

from __future__ import annotations

from dataclasses import replace
from functools import cache

import pytest

from ci.conformance.lies import LIES, LyingRuns, is_a_lie, shortest_beyond
from ci.conformance.properties import PROPERTIES, RUNS, LieKind, PropertyName, Run, Runs, Verdict, register
from spec.engines import load_engines
from spec.scenario import Scenario

ALL_ENGINES = ("interpreter", "spin", "z3")


@cache
def honest_runs(scenario: Scenario) -> Runs:
    """One scenario's honest runs, made once for every lie told on it."""
    return Runs(scenario)


def test_every_lie_kind_has_a_stub_engine_and_a_property_that_exists_to_catch_it() -> None:
    assert set(LIES) == set(LieKind)
    claimed = {kind for prop in PROPERTIES.values() for kind in prop.lies}
    assert claimed == set(LieKind), f"lies no property claims: {set(LieKind) - claimed}"


@pytest.mark.requires_spin
@pytest.mark.parametrize("kind", list(LieKind), ids=lambda k: k.value)
def test_every_stub_tells_a_real_lie(kind: LieKind) -> None:
    """Judged without the properties: a lie that turned out true would make a test that cannot fail."""
    lie = LIES[kind]
    scenario = lie.scenario()
    honest = honest_runs(scenario).get(lie.liar)
    assert honest.answer is not None, honest.error
    told = lie.tell(scenario, honest.answer)
    assert is_a_lie(lie, scenario, honest.answer, told), f"{kind.value}: {told}"


@pytest.mark.requires_spin
@pytest.mark.parametrize("name", list(PROPERTIES), ids=lambda n: n.value)
def test_every_property_fails_on_each_of_its_lies_and_holds_on_the_honest_engines(name: PropertyName) -> None:
    prop = PROPERTIES[name]
    assert prop.lies, f"{name.value} is registered without the lies it exists to catch"
    assert prop.applies(ALL_ENGINES)
    for kind in prop.lies:
        scenario = LIES[kind].scenario()
        honest = prop.verdict(scenario, honest_runs(scenario), ALL_ENGINES)
        assert honest.verdict is Verdict.HELD, f"{name.value} on the honest engines ({kind.value}): {honest.detail}"
        for lie in LIES[kind].told_to(prop):
            truth = honest_runs(scenario).get(lie.liar).answer
            told = f"{kind.value} told by {lie.liar.label}"
            assert truth is not None and is_a_lie(lie, scenario, truth, lie.tell(scenario, truth)), f"no lie: {told}"
            lying = prop.verdict(scenario, LyingRuns(honest_runs(scenario), lie), ALL_ENGINES)
            assert lying.verdict is Verdict.FAILED, f"{name.value} did not catch {told}: {lying}"


def test_every_registered_engine_is_read_by_the_properties_and_so_lied_about() -> None:
    """A new engine has no place to hide: the properties read every registered engine (``RUNS``), and every lie is
    told by every run its property reads."""
    assert {key.engine for key in RUNS} == set(load_engines())
    assert {key for prop in PROPERTIES.values() for key in prop.runs} == set(RUNS)


@pytest.mark.requires_spin
@pytest.mark.parametrize("horizon_short_by", [1, 3])
def test_no_plan_proof_searches_beyond_the_horizon(horizon_short_by: int) -> None:
    """A false "no plan of any length" whose shortest counterexample is 1 or 3 actions longer than the horizon."""
    lie = LIES[LieKind.NO_PLAN_ONE_BEYOND if horizon_short_by == 1 else LieKind.NO_PLAN_BEYOND]
    scenario = lie.scenario()
    assert shortest_beyond(scenario) == scenario.horizon + horizon_short_by
    outcome = PROPERTIES[PropertyName.NO_PLAN_PROOF].verdict(scenario, LyingRuns(honest_runs(scenario), lie),
                                                              ALL_ENGINES)
    assert outcome.verdict is Verdict.FAILED and f"has one of {scenario.horizon + horizon_short_by}" in outcome.detail


def test_a_property_without_lies_cannot_be_registered() -> None:
    existing = PROPERTIES[PropertyName.EXISTENCE]
    with pytest.raises(ValueError, match="without its lies"):
        register(replace(existing, lies=()))
    assert PROPERTIES[PropertyName.EXISTENCE] is existing


def test_a_liar_without_an_honest_answer_is_a_clear_error() -> None:
    lie = LIES[LieKind.WRONG_PLAN]
    runs = Runs(lie.scenario())
    runs._made[lie.liar.label] = Run(lie.liar, None, "crashed", 1.0)
    with pytest.raises(ValueError, match="no honest answer"):
        LyingRuns(runs, lie).get(lie.liar)
