"""The hypothesis source of ``overtake crossval``: hypothesis generates and shrinks the scenarios.

One hypothesis test per property, each run as one job (so properties run in parallel and one
property's failure never stops another's): every example it tries is checked and its verdict
appended to ``OUT/verdicts.jsonl`` at once (one ``write`` per line on a file opened for
appending, so parallel jobs never tear each other's lines). Failing examples are kept in
``OUT/hypothesis/<property>`` (hypothesis's example database) and replayed first next time.
The example hypothesis shrank a failure to is the reproducer's scenario. Profiles: ``dev``
(fast) and ``ci`` (thorough), chosen by ``HYPOTHESIS_PROFILE``; the seed is printed.
"""

from __future__ import annotations

import contextlib
import json
import os
from dataclasses import replace
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, Verbosity, given, settings
from hypothesis import seed as hypothesis_seed
from hypothesis import strategies as st
from hypothesis.database import DirectoryBasedExampleDatabase
from rich.console import Console

from ci.conformance.crossval import DRAWN, VERDICTS_FILE, Campaign, check_resumable, check_scenario, recorded
from ci.conformance.properties import PropertyName, Verdict
from ci.shared.executors import ExecutorChoice, run_jobs
from ci.shared.records import campaign_lock
from spec import assumptions
from spec.assumptions import Bounds, SpeedBounds
from spec.constants import DEFAULT_HORIZON
from spec.dynamics import Overtaken
from spec.engines import get_engine
from spec.envelope import TRACKING
from spec.errors import ScenarioError
from spec.escapes import ALL_KINDS, Commitment, EscapeKind
from spec.files import scenario_from_dict
from spec.grid import PAPER_GRID, Grid, grid_for
from spec.lanes import Lane
from spec.physical import LOOP
from spec.scenario import Scenario, make_scenario, measured_speeds, sensed
from spec.sound import Sound, sensed_extents

#: The campaign's own profiles (the tests register theirs in tests/conftest.py), picked by ``PROFILE_VAR``.
#: Quiet: hypothesis would print its falsifying examples from the workers into the command's output (and --json);
#: the failures are in the verdicts and the reproducers instead.
PROFILES = {
    "dev": settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow],
                    verbosity=Verbosity.quiet),
    "ci": settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow],
                   verbosity=Verbosity.quiet),
}
PROFILE_VAR = "HYPOTHESIS_PROFILE"


def profile() -> str:
    """The profile ``PROFILE_VAR`` names (default ``dev``); an unknown name is bad input."""
    from spec.errors import OptionError

    name = os.environ.get(PROFILE_VAR, "dev")
    if name not in PROFILES:
        raise OptionError(PROFILE_VAR, name, f"unknown hypothesis profile (known: {', '.join(PROFILES)})")
    return name


def _speed_choices() -> tuple[SpeedBounds, ...]:
    paper, default = assumptions.PROFILES["paper"].same_mps, assumptions.PROFILES[assumptions.DEFAULT_PROFILE].same_mps
    half = SpeedBounds((paper.low_mps + default.low_mps) / 2, (paper.high_mps + default.high_mps) / 2)
    return paper, half, default


#: The bounds the hypothesis source draws with each scenario (``--model sound`` with no bounds option), stated: each
#: lane's speeds from the paper profile's single speed to the default profile's interval (the spread traffic's
#: cut-off), in three steps (the ends and halfway); the sensing error none or the default profile's; phantoms on or
#: off; followers that react or keep their speed; a planning latency of none or one control step (``LATENCY_CHOICES``).
#: A lattice, not a continuum: every distinct set of bounds is a verifier Spin compiles (144 here, cached), and the
#: ends are the profiles the suite ships.
SPEED_CHOICES = _speed_choices()
ERROR_CHOICES = (assumptions.PROFILES["paper"].sensing_error_m,
                 assumptions.PROFILES[assumptions.DEFAULT_PROFILE].sensing_error_m)
#: The planning latency: none (the plan acts at the snapshot's instant) or the closed loop's budget (one control step,
#: ``spec.physical.LOOP.plan_budget_s``): the two the suite plans with.
LATENCY_CHOICES = (0.0, LOOP.plan_budget_s)


#: Where a snapshot's view of the oncoming lane may end (``Sound.oncoming_view_m``: a left-lane vehicle hides the lane
#: from there on), in the paper's 21 m cells ahead of the AV, stated: behind a vehicle in the next cell, two and five
#: cells ahead (the middle of each), the same distances on every grid; none (the sensor's whole range) half the time.
VIEW_CELLS = (1.5, 2.5, 5.5)
VIEWS_M = tuple(c * float(PAPER_GRID.cell) for c in VIEW_CELLS)  # the same, in metres


@st.composite
def drawn_sound(draw: st.DrawFn) -> Sound:
    """Bounds from the stated choices (shrinking towards the paper profile's), a sideways move under way or none, the
    sensors at the plan's reference or off it, the plan's AV the car or that reference (``Sound.from_reference``),
    and the vehicles sensed as readings or as sets that hold the sensing error (``Sound.sensed_sets``: a quarter of
    the time, shrinking towards readings)."""
    same, oncoming = draw(st.sampled_from(SPEED_CHOICES)), draw(st.sampled_from(SPEED_CHOICES))
    error, phantoms = draw(st.sampled_from(ERROR_CHOICES)), draw(st.sampled_from((True, False)))
    react, latency = draw(st.sampled_from((True, False))), draw(st.sampled_from(LATENCY_CHOICES))
    name = (f"drawn: same {same.low_mps:g}..{same.high_mps:g}, oncoming {oncoming.low_mps:g}..{oncoming.high_mps:g}, "
            f"error {error:g} m, phantoms {'on' if phantoms else 'off'}, followers "
            f"{'react' if react else 'keep their speed'}, latency {latency:g} s")
    source = "drawn by the hypothesis source (ci.conformance.hypo.SPEED_CHOICES, ERROR_CHOICES, LATENCY_CHOICES)"
    return Sound(Bounds(name, same, oncoming, error, phantoms, source, react, latency),
                 sideways_s=draw(st.sampled_from(SIDEWAYS_CHOICES)),
                 sensors_ahead_m=draw(st.sampled_from(SENSORS_AHEAD_CHOICES)),
                 sensed_sets=draw(st.sampled_from((False, False, False, True))),
                 from_reference=draw(st.sampled_from((False, True))))


#: A sideways move under way at the start, as the hypothesis source draws it (``spec.sound.Sound.sideways_s``): none
#: most of the time (shrinking towards none), a move just begun or about to end, a whole one.
SIDEWAYS_CHOICES = (0.0, 0.0, 0.0, 0.5, TRACKING.lateral_s)
#: Where the car's sensors stood ahead of the plan's reference (``spec.sound.Sound.sensors_ahead_m``): at it most of
#: the time (shrinking towards it), or at either edge of the envelope's position error.
SENSORS_AHEAD_CHOICES = (0.0, 0.0, 0.0, -TRACKING.position_m, TRACKING.position_m)


#: The commitments the hypothesis source draws under the commitment semantics, stated: as many actions as are proved
#: (the default, half the time), or at most one, two or three; every escape, or the minimal-risk manoeuvre with aborts
#: only or with completions only (``spec.escapes.EscapeKind``).
MOST_ACTIONS = (None, None, 1, 2, 3)
ESCAPE_CHOICES = (ALL_KINDS, (EscapeKind.MINIMAL_RISK, EscapeKind.ABORT),
                  (EscapeKind.MINIMAL_RISK, EscapeKind.COMPLETE))


def commitments() -> st.SearchStrategy[Commitment]:
    """A commitment from the stated choices (shrinking towards the default, ``COMMIT``)."""
    return st.builds(Commitment, st.sampled_from(MOST_ACTIONS), st.sampled_from(ESCAPE_CHOICES))


def speeds(lane: SpeedBounds, count: int) -> st.SearchStrategy[list[tuple[float, float]]]:
    """Measured speed intervals for ``count`` vehicles of a lane with ``lane``'s speeds: standing, anything from a
    standstill to the top, narrow readings anywhere from below the lane's slowest to above its top."""
    narrow = st.tuples(st.floats(0.0, lane.high_mps + 1.0), st.floats(0.0, 1.5)).map(lambda p: (p[0], p[0] + p[1]))
    one = st.one_of(st.just((0.0, 0.0)), st.just((0.0, lane.high_mps)), narrow)
    return st.lists(one, min_size=count, max_size=count)


@st.composite
def with_speeds(draw: st.DrawFn, scenario: Scenario, profiles: bool = True) -> Scenario:
    """``scenario`` (under the sound model) with its same-direction vehicles' speeds measured, and, half the time,
    the oncoming ones' too (``spec.scenario.measured_speeds``); with ``profiles``, under either profile of vehicles
    overtaken (``spec.dynamics.Overtaken``)."""
    assert scenario.sound is not None
    b = scenario.sound.bounds
    left = draw(speeds(b.same_mps, len(scenario.left_lane)))
    right = draw(st.none() | speeds(b.oncoming_mps, len(scenario.right_lane)))
    if profiles:
        scenario = replace(scenario, sound=replace(scenario.sound, overtaken=draw(st.sampled_from(list(Overtaken)))))
    return measured_speeds(scenario, left, right)


def scenarios(grid: Grid, horizon: int | None, model: Sound | str | None = None, measured: bool = False,
              profiles: bool = False, commit: bool = False) -> st.SearchStrategy[Scenario]:
    """Valid scenarios on ``grid``: up to 4 same-direction and 2 oncoming vehicles anywhere in the window, either
    lane, any target count; drawn near the AV first (hypothesis shrinks towards small cells, so the window's
    start is put at the AV's cell and cells count outwards from it). Under ``model`` (``Campaign.sound``): the
    paper's rules (None), that sound model, or one drawn with each scenario (``DRAWN``); under the sound model, half
    the time what the snapshot measured of each vehicle's place, and with ``measured`` (every engine of the
    campaign answers it) half the time each vehicle's own speed (``with_speeds``; under either profile of vehicles
    overtaken with ``profiles``, every engine answering both); with ``commit``, under the commitment semantics, a
    commitment drawn with each scenario (``commitments``)."""
    cells = st.integers(0, grid.road_cells)

    @st.composite
    def build(draw: st.DrawFn) -> Scenario:
        lane = draw(st.sampled_from([Lane.LEFT, Lane.RIGHT]))
        left = draw(st.lists(cells, max_size=4, unique=True))
        right = draw(st.lists(cells, max_size=2, unique=True))
        ahead = sum(1 for c in left if c >= grid.av_cell)
        targets = draw(st.integers(0, min(ahead, 3)))
        h = horizon if horizon is not None else draw(st.integers(1, DEFAULT_HORIZON))
        sound = draw(drawn_sound()) if model == DRAWN else model if isinstance(model, Sound) else None
        if sound is not None and sound.oncoming_view_m is None:
            view = draw(st.sampled_from((None, None, None, *VIEWS_M)))
            sound = sound if view is None else replace(sound, oncoming_view_m=view)
        if sound is not None and commit:
            sound = replace(sound, commitment=draw(commitments()))
        try:
            scenario = replace(make_scenario(lane, left, right, targets, horizon=h, grid=grid), sound=sound)
        except ScenarioError:
            from hypothesis import reject

            reject()
            raise  # unreachable: reject() raises
        if sound is None:
            return scenario
        if draw(st.booleans()):
            scenario = draw(sensed_places(scenario))
        return draw(with_speeds(scenario, profiles)) if measured and draw(st.booleans()) else scenario

    return build()


@st.composite
def sensed_places(draw: st.DrawFn, scenario: Scenario) -> Scenario:
    """``scenario`` with what a snapshot measured (``spec.scenario.sensed``): per vehicle a reading anywhere in its
    cell's extent, or an interval inside it (a kept track); shrinking towards the cell's extent itself."""
    same, oncoming = sensed_extents(scenario.lane, scenario.left_lane, scenario.right_lane, scenario.grid)

    def inside(extent: tuple[float, float]) -> tuple[float, float]:
        lo, hi = extent
        a = draw(st.floats(0.0, 1.0))
        b = draw(st.sampled_from((1.0, 0.25, 0.0)))  # the rest of the extent, a short interval, a reading
        start = lo + a * (hi - lo)
        return start, start + b * (hi - start)

    return sensed(scenario, tuple(inside(e) for e in same), tuple(inside(e) for e in oncoming))


class PropertyFailed(AssertionError):
    """A property failed on an example (hypothesis then shrinks it)."""


def hypothesis_job(name: str, campaign: Campaign, out_dir: str, profile_name: str, offset: int,
                   report: Any = None) -> dict[str, Any]:
    """One property's hypothesis test (a worker's job, seeded with the campaign's seed + ``offset`` so that the
    properties see different examples): the examples' verdicts appended as they come; returns the shrunk failing
    example, if any."""
    grid = grid_for(campaign.cell_m)
    out = Path(out_dir)
    fd = os.open(out / VERDICTS_FILE, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    last_failure: dict[str, Any] = {}
    done = recorded(out / VERDICTS_FILE, campaign)
    prop = PropertyName(name)

    @hypothesis_seed((campaign.seed or 0) + offset)
    @settings(PROFILES[profile_name], max_examples=campaign.count or PROFILES[profile_name].max_examples,
              database=DirectoryBasedExampleDatabase(str(out / "hypothesis" / name)))
    @given(scenarios(grid, campaign.horizon, campaign.sound,
                     all(campaign.semantics in get_engine(e).measured_speeds for e in campaign.engines),
                     all(campaign.semantics in get_engine(e).overtaken_profile for e in campaign.engines),
                     campaign.commit))
    def test(scenario: Scenario) -> None:
        result = check_scenario(scenario, [prop], campaign.engines, campaign.timeout_s)
        if name not in done.get(result["key"], {}).get("verdicts", {}):
            os.write(fd, (json.dumps({"campaign": campaign.key(), "result": result}) + "\n").encode())
            done[result["key"]] = result
        if report is not None:
            report(1)
        verdict, detail = result["verdicts"][name]
        if verdict == Verdict.FAILED.value:
            last_failure.clear()
            last_failure.update(result)
            raise PropertyFailed(detail)

    try:
        test()
    except PropertyFailed:
        pass  # hypothesis ran the shrunk example last: it is in last_failure
    finally:
        os.close(fd)
    return {"property": name, "failure": dict(last_failure) or None}


def run_hypothesis(campaign: Campaign, out: Path, executor: ExecutorChoice, max_reproducers: int,
                   console: Console) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Every property's hypothesis test; the recorded results of this campaign and the reproducers written."""
    with campaign_lock(out):
        return _run(campaign, out, executor, max_reproducers, console)


def _run(campaign: Campaign, out: Path, executor: ExecutorChoice, max_reproducers: int,
         console: Console) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    from ci.conformance.repro import reproduce

    (out / VERDICTS_FILE).touch()
    check_resumable(out / VERDICTS_FILE, campaign)
    name = profile()
    console.print(f"crossval: hypothesis profile {name} ({PROFILE_VAR}), seed {campaign.seed}"
                  + (f", {campaign.count} examples per property (--count)" if campaign.count else ""))
    jobs = [(p.value, campaign, str(out), name, n) for n, p in enumerate(campaign.properties)]
    reproducers = []
    shrunk: dict[str, dict[str, Any]] = {}
    with contextlib.closing(run_jobs(hypothesis_job, jobs, executor)) as finished:
        for _, job in finished:
            if job["failure"] is not None:
                shrunk[job["property"]] = job["failure"]
    results = list(recorded(out / VERDICTS_FILE, campaign).values())
    for prop_name, failure in shrunk.items():
        if max_reproducers:
            console.print(f"crossval: {prop_name} failed; hypothesis shrank it to {failure['key']}")
            reproducers.append(reproduce(PropertyName(prop_name), scenario_from_dict(failure["scenario"]),
                                         campaign.engines, campaign.timeout_s, out, 1, "hypothesis"))
    return results, reproducers
