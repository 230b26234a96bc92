"""The engine registry: every declared engine loads and registers once; unknown names and strategies are bad input."""

from __future__ import annotations

import pytest

from spec.answers import Strategy
from spec.engines import ENGINES, check_strategy, engine_names, get_engine, load_engines, parse_strategy
from spec.errors import ExitCode, OptionError


def test_the_three_engines_are_declared_and_each_registers_under_its_name() -> None:
    assert set(engine_names()) >= {"interpreter", "spin", "z3"}
    loaded = load_engines()
    assert {"interpreter", "spin", "z3"} <= set(loaded)
    assert all(name == engine.name for name, engine in loaded.items())
    assert all(engine.strategies and all(isinstance(s, Strategy) for s in engine.strategies)
               for engine in loaded.values())


def test_every_strategy_is_answered_by_some_engine() -> None:
    answered = {s for engine in load_engines().values() for s in engine.strategies}
    assert answered == set(Strategy)


def test_unknown_engine_and_strategy_are_bad_input_never_a_default() -> None:
    with pytest.raises(OptionError, match=r"--engine='quantum': unknown engine \(known: .*interpreter"):
        get_engine("quantum")
    with pytest.raises(OptionError, match=r"--strategy='fastest'"):
        parse_strategy("fastest")
    with pytest.raises(OptionError, match=r"engine z3 answers shortest, optimal only"):
        check_strategy(ENGINES["z3"] if "z3" in ENGINES else get_engine("z3"), Strategy.SENSIBLE)
    assert OptionError.exit_code is ExitCode.BAD_INPUT
