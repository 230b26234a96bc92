"""The engine registry: every engine is registered once, with the strategies it answers.

An engine is a solver of ``Problem``s. The engines live in the layers above (``oracle/``,
``promela/``), which this module never imports: each is declared as an entry point of the
group ``overtake_mc.engines`` in ``pyproject.toml`` and registers itself when that entry point
is loaded, so the registry is complete without a lower layer naming a higher one. Tests are
parametrised over ``load_engines()`` and fail when an engine skips a strategy it claims.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from importlib.metadata import entry_points

from spec.answers import Limits, SearchResult, Strategy
from spec.dynamics import Overtaken
from spec.errors import OptionError, ToolMissing
from spec.escapes import COMMIT, Semantics
from spec.scenario import Problem, Scenario

Solver = Callable[[Problem, Strategy, Limits], SearchResult]
ENTRY_POINTS = "overtake_mc.engines"


@dataclass(frozen=True, slots=True)
class Engine:
    """A registered engine: its name, the strategies it answers, and how it solves a problem."""

    name: str
    strategies: tuple[Strategy, ...]
    solve: Solver
    description: str
    #: Given a problem with no plan within the horizon, proves (NO_PLAN) or not that none exists at all.
    prove_beyond: Callable[[Problem], SearchResult] | None = None
    #: Raises ToolMissing (with what to install) when an outside tool the engine runs is missing.
    check_tools: Callable[[], None] | None = None
    #: Whether it answers the sound model (a scenario with ``sound`` set); the others answer the paper's rules only.
    sound: bool = False
    #: Whether it answers the sound model's commitment semantics (``spec.escapes``); the others its whole plans only.
    commit: bool = False
    #: The semantics under which it answers vehicles with their own measured speeds (``Scenario.left_mps``,
    #: ``spec.dynamics``); under the others it answers every vehicle at its lane's speeds only.
    measured_speeds: tuple[Semantics, ...] = ()
    #: The semantics under which it answers the no-acceleration profile (``spec.dynamics.Overtaken``) for such
    #: vehicles; under the others it answers their physics only.
    overtaken_profile: tuple[Semantics, ...] = ()

    def ready(self) -> None:
        """Check, before any work, that the engine can run here (exit 4 with the install command if not)."""
        if self.check_tools is not None:
            self.check_tools()


ENGINES: dict[str, Engine] = {}


def register(engine: Engine) -> Engine:
    """Add an engine to the registry (once)."""
    if engine.name in ENGINES:
        raise ValueError(f"engine {engine.name!r} registered twice")
    ENGINES[engine.name] = engine
    return engine


def _declared() -> dict[str, object]:
    """The entry points that declare engines, by name."""
    return {ep.name: ep for ep in entry_points(group=ENTRY_POINTS)}


def load_engines() -> dict[str, Engine]:
    """Load every declared engine, so that the registry is complete, and return it."""
    for name, ep in _declared().items():
        if name not in ENGINES:
            ep.load()  # type: ignore[attr-defined]
    return ENGINES


def engine_names() -> list[str]:
    """Every engine's name, registered or declared, without loading any."""
    return list(dict.fromkeys([*ENGINES, *_declared()]))


def get_engine(name: str) -> Engine:
    """The engine called ``name``, loaded on first use; an unknown name is bad input."""
    if name not in ENGINES:
        ep = _declared().get(name)
        if ep is not None:
            ep.load()  # type: ignore[attr-defined]
    if name not in ENGINES:
        known = engine_names()
        if not known:
            raise ToolMissing("no engine is declared: overtake-mc is not installed (run `bash ci/setup.sh`, or "
                              "`pip install -e .` in the checkout)")
        raise OptionError("--engine", name, f"unknown engine (known: {', '.join(known)})")
    return ENGINES[name]


def parse_strategy(text: str | Strategy) -> Strategy:
    """The strategy called ``text``; an unknown one is bad input, never a default."""
    if isinstance(text, Strategy):
        return text
    try:
        return Strategy(text)
    except ValueError:
        raise OptionError("--strategy", text, f"unknown strategy (known: {', '.join(s.value for s in Strategy)})") \
            from None


def check_model(engine: Engine, scenario: Scenario) -> None:
    """Raise bad input when ``scenario`` asks for the sound model and ``engine`` answers the paper's rules only, for
    the sound model's commitment semantics and ``engine`` answers its whole plans only, or gives vehicles their own
    measured speeds and ``engine`` moves every vehicle at its lane's speeds only."""
    if scenario.sound is not None and not engine.sound:
        able = ", ".join(e.name for e in load_engines().values() if e.sound) or "none"
        raise OptionError("--bounds", scenario.sound.bounds.name, f"engine {engine.name} answers the paper model "
                          f"only; the sound model is answered by: {able}")
    if scenario.sound is not None and scenario.sound.commitment is not None and not engine.commit:
        able = ", ".join(e.name for e in load_engines().values() if e.commit) or "none"
        raise OptionError("--semantics", "commit", f"engine {engine.name} answers the sound model's whole plans only "
                          f"(--semantics whole); committed actions with an escape are answered by: {able}")
    given = [(k, v) for k, v in (("left_mps", scenario.left_mps), ("right_mps", scenario.right_mps)) if v is not None]
    semantics = semantics_of(scenario)
    if scenario.sound is not None and given and semantics not in engine.measured_speeds:
        able = ", ".join(e.name for e in load_engines().values() if semantics in e.measured_speeds) or "none"
        raise OptionError(given[0][0], [list(s) for s in given[0][1]], f"engine {engine.name} answers every vehicle "
                          f"at its lane's speeds only{_under(engine.measured_speeds, semantics)}; vehicles with their "
                          f"own measured speeds are answered by: {able}")
    if scenario.sound is not None and scenario.left_mps and scenario.sound.overtaken is not Overtaken.PHYSICS \
            and semantics not in engine.overtaken_profile:
        able = ", ".join(e.name for e in load_engines().values() if semantics in e.overtaken_profile) or "none"
        raise OptionError("--overtaken", scenario.sound.overtaken.value, f"engine {engine.name} answers measured "
                          f"vehicles by their physics only{_under(engine.overtaken_profile, semantics)}; the "
                          f"{scenario.sound.overtaken.value} profile is answered by: {able}")


def semantics_of(scenario: Scenario) -> Semantics:
    """How ``scenario``'s sound model answers: its commitment semantics, or whole plans (the paper's rules too)."""
    sound = scenario.sound
    return Semantics.COMMIT if sound is not None and sound.commitment is not None else Semantics.WHOLE


def under_semantics(scenario: Scenario, semantics: Semantics) -> Scenario:
    """``scenario`` with its sound model answering under ``semantics`` (the default commitment, or whole plans); the
    paper's rules as they are."""
    if scenario.sound is None:
        return scenario
    return replace(scenario, sound=replace(scenario.sound, commitment=COMMIT if semantics is Semantics.COMMIT
                                           else None))


def _under(able: tuple[Semantics, ...], semantics: Semantics) -> str:
    """Where an engine answers a feature under other semantics than ``semantics``: which (for its refusal)."""
    if not able:
        return ""
    return f" under --semantics {semantics.value} (it answers them under --semantics " \
           f"{', '.join(s.value for s in able)})"


def answers(engine: Engine, scenario: Scenario) -> bool:
    """Whether ``engine`` answers ``scenario``'s model (``check_model`` finds nothing to refuse)."""
    try:
        check_model(engine, scenario)
    except OptionError:
        return False
    return True


def check_strategy(engine: Engine, strategy: Strategy) -> None:
    """Raise bad input when ``engine`` does not answer ``strategy``."""
    if strategy not in engine.strategies:
        answers = ", ".join(s.value for s in engine.strategies)
        raise OptionError("--strategy", strategy.value, f"engine {engine.name} answers {answers} only")
