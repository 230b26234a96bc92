"""The Spin engine's sound model (``promela.sound``) agrees with the interpreter's (``oracle.sound``): same plan or no
plan through the pipeline, every plan valid with the validation's states, identical sensible plans, equal shortest
lengths; one verifier per sound model; the identity check refused.

The seeded sample (``SAMPLE``: lanes both, 0-2 left-lane vehicles in paper cells 8..20, 0-1 oncoming in 12..30,
targets 0..len, horizon 30) runs by default; ``OVERTAKE_SOUND_SAMPLE=N`` multiplies it by N (another seed per
round) for a larger one.
"""

from __future__ import annotations

import os
import random
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ci.conformance.hypo import VIEWS_M, with_speeds
from oracle import planner, sound
from promela import runner
from promela import sound as sound_model
from spec.actions import Action
from spec.answers import Limits, Status, Strategy
from spec.assumptions import Bounds, SpeedBounds, profile
from spec.cells import left_extent_m
from spec.dynamics import Overtaken
from spec.errors import EngineError
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid, grid_for
from spec.lanes import Lane
from spec.models import ModelKind
from spec.physical import LOOP
from spec.scenario import Scenario, make_scenario, measured_speeds, problem_for, sensed
from spec.sound import Checks, Sound, sound_from
from tests.conftest import AGED_SHORTEST_LENGTH, CI_PROFILE, check_aged_witness, measured_like, measured_pinned
from tests.oracle.test_sound import sound_scenarios
from tests.oracle.test_sound_measured import _least_accepted_m, _overtaking, _standing_ahead

pytestmark = pytest.mark.requires_spin

#: (profile, cell length, scenarios): about 170 scenarios, both strategies each.
SAMPLE = (("default", 21.0, 70), ("default", 10.5, 70), ("paper", 21.0, 15), ("paper", 10.5, 15))
ROUNDS = int(os.environ.get("OVERTAKE_SOUND_SAMPLE", "1"))


def _draw(rng: random.Random, grid: Grid, sound_: Sound) -> Scenario:
    """A scenario of the sample: paper cells scaled to the grid, none in the AV's cell in its own lane."""
    scale = round(PAPER_GRID.cell / grid.cell)
    lane = rng.choice(list(Lane))
    left = [c for c in rng.sample(range(8 * scale, 20 * scale + 1), rng.randint(0, 2))
            if not (lane is Lane.LEFT and c == grid.av_cell)]
    right = rng.sample(range(12 * scale, 30 * scale + 1), rng.randint(0, 1))
    ahead = sum(1 for c in left if c >= grid.av_cell)
    return replace(make_scenario(lane, left, right, rng.randint(0, ahead), horizon=30, grid=grid), sound=sound_)


def _agree(scenario: Scenario, strategy: Strategy) -> tuple[float, bool]:
    """Spin's pipeline answer against the interpreter's; Spin's time, and whether it is a plan."""
    started = time.perf_counter()
    spin = planner.solve(scenario, strategy, engine="spin")
    took = time.perf_counter() - started
    ours = planner.solve(scenario, strategy, engine="interpreter")
    where = f"{scenario} {strategy.value}: spin {spin.status.value} {spin.actions}, interpreter {ours.status.value} " \
            f"{ours.actions}"
    assert (spin.status is Status.PLAN) == (ours.status is Status.PLAN), where
    assert spin.status is not Status.INCOMPLETE, where
    if spin.status is Status.PLAN:
        assert spin.model is ours.model and spin.model is not None, where
        verdict = sound.validate(problem_for(scenario, spin.model), spin.actions)
        assert verdict.valid, f"{where}: {verdict.reason}"
        assert spin.states == verdict.states, where
        if strategy is Strategy.SENSIBLE:
            assert spin.actions == ours.actions, where
        else:
            assert len(spin.actions) == len(ours.actions), where
    return took, spin.status is Status.PLAN


@pytest.mark.parametrize(("name", "cell_m", "count"), SAMPLE, ids=[f"{n}-{c:g}m" for n, c, _ in SAMPLE])
def test_the_pipeline_agrees_with_the_interpreter_on_a_seeded_sample(name: str, cell_m: float, count: int) -> None:
    grid, sound_ = grid_for(cell_m), Sound(profile(name))
    started, times, plans = time.perf_counter(), [], 0
    for round_ in range(ROUNDS):
        rng = random.Random(f"sound-spin-{name}-{cell_m}-{round_}")
        for _ in range(count):
            scenario = _draw(rng, grid, sound_)
            for strategy in (Strategy.SENSIBLE, Strategy.SHORTEST):
                took, planned = _agree(scenario, strategy)
                times.append(took)
                plans += planned
    print(f"\n{name} {cell_m:g} m: {count * ROUNDS} scenarios x 2 strategies, {plans} plans, in "
          f"{time.perf_counter() - started:.1f} s; spin's pipeline median {statistics.median(times) * 1000:.1f} ms")
    assert plans > 0


def test_a_measured_start_speed_agrees_too() -> None:
    """Early windows (the ramp from the measured speed into the first action) in play."""
    rng = random.Random("sound-spin-start-speed")
    for start_mps in (3.0, 9.5):
        for _ in range(10):
            scenario = _draw(rng, PAPER_GRID, Sound(profile("default"), start_mps=start_mps))
            _agree(scenario, Strategy.SENSIBLE)


def test_an_oncoming_view_ended_short_agrees_too_from_one_verifier() -> None:
    """The oncoming phantom where a left-lane vehicle hid the lane (``Sound.oncoming_view_m``, the hypothesis source's
    views), its edge read with the scenario so that one verifier serves every view: Spin's answers are the
    interpreter's, and the view changes some of them."""
    rng, changed = random.Random("sound-spin-view"), 0
    for _ in range(16):
        seen = _draw(rng, PAPER_GRID, Sound(profile("default")))
        assert seen.sound is not None
        hidden = replace(seen, sound=replace(seen.sound, oncoming_view_m=rng.choice(VIEWS_M)))
        _agree(hidden, Strategy.SENSIBLE)
        changed += planner.solve(hidden, Strategy.SENSIBLE).actions != planner.solve(seen, Strategy.SENSIBLE).actions
        one, other = (sound_model.shape_of(problem_for(s, ModelKind.FINAL)) for s in (seen, hidden))
        assert one.name == other.name
    assert changed > 0


#: Scenarios that told a faulty translation from the interpreter where the sample did not (cell length, profile,
#: measured start speed, lane, left, right, targets): the oncoming vehicles' lower end moved at their lowest speed;
#: the early windows (the first ramp still running) left out. Then two whose answer the paper profile's followers
#: (who keep their speed: ``Conflict.BEHIND``) change: a slow AV must get back to their speed, and a return whose
#: braking a follower would run into.
PINNED = ((21.0, "default", 3.0, "right", (16,), (13, 34), 1), (5.25, "paper", 9.5, "right", (38, 46), (), 0),
          (21.0, "paper", 5.0, "left", (12, 13, 15, 17), (), 0), (21.0, "paper", 5.0, "right", (8, 12, 14, 16),
                                                                  (18, 23), 1))


@pytest.mark.parametrize("case", PINNED, ids=lambda c: f"{c[1]}-{c[0]:g}m-{c[2]:g}mps")
def test_pinned_scenarios_agree(case: tuple[float, str, float, str, tuple[int, ...], tuple[int, ...], int]) -> None:
    cell_m, name, start_mps, lane, left, right, targets = case
    scenario = make_scenario(lane, list(left), list(right), targets, horizon=30, grid=grid_for(cell_m))
    for strategy in (Strategy.SENSIBLE, Strategy.SHORTEST):
        _agree(replace(scenario, sound=Sound(profile(name), start_mps=start_mps)), strategy)


# -- one verifier per shape, a table per sound model -----------------------------------------------------------
#: A scenario whose sensible plan differs between the profiles: each must be answered with its own bounds.
DIFFERS = ("right", (12,), (), 1)


def test_two_profiles_share_one_verifier_each_answering_with_its_own_table() -> None:
    lane, left, right, targets = DIFFERS
    base = make_scenario(lane, list(left), list(right), targets, horizon=30)
    answers, paths, tables = {}, {}, {}
    for name in ("default", "paper"):
        scenario = replace(base, sound=Sound(profile(name)))
        problem = problem_for(scenario, ModelKind.FINAL)
        shape = sound_model.shape_of(problem)
        assert shape.name.startswith("sound-final-overtake-p")
        paths[name] = runner.verifier(shape, Strategy.SENSIBLE).path
        tables[name] = runner.table_file(problem)
        spin = runner.search(problem, Strategy.SENSIBLE)
        ours = sound.solve(problem, Strategy.SENSIBLE, Limits())
        assert (spin.status, spin.actions, spin.states) == (ours.status, ours.actions, ours.states)
        answers[name] = (spin.status, spin.actions)
    assert paths["default"] == paths["paper"]
    assert tables["default"] != tables["paper"]
    assert answers["default"] != answers["paper"]


def test_a_served_verifier_answers_each_request_with_its_own_table_read_before_its_fork(tmp_path: Path) -> None:
    """The server reads a request's table before it forks the run (``sound_prepare``, once per table): requests that
    alternate between two tables of one verifier each get their own table's answer, the same as a verifier run on
    its own; a table that will not read is the run's to report (exit 2, one line), and the server serves on."""
    lane, left, right, targets = DIFFERS
    base = make_scenario(lane, list(left), list(right), targets, horizon=30)
    problems = {name: problem_for(replace(base, sound=Sound(profile(name))), ModelKind.FINAL)
                for name in ("default", "paper")}
    alone = {name: runner.search(p, Strategy.SENSIBLE, serve=False) for name, p in problems.items()}
    assert alone["default"].actions != alone["paper"].actions
    built = runner.verifier(sound_model.shape_of(problems["paper"]), Strategy.SENSIBLE)
    server = runner.Server(built.path)
    try:
        bad = tmp_path / "table.txt"
        whole = sound_model.table_text(sound_model.table_sound(problems["paper"]), problems["paper"].grid)
        bad.write_text(whole[: len(whole) // 2])
        for name in ("paper", "default", "default", "paper", "default"):  # through the pipeline's own server
            found = runner.search(problems[name], Strategy.SENSIBLE)
            assert (found.status, found.actions, found.states) == (alone[name].status, alone[name].actions,
                                                                   alone[name].states), name
        summary = {}  # pan's closing summary on each table, run on its own
        for name, problem in problems.items():
            env = {**os.environ, "OVERTAKE_SCENARIO": runner.injected(problem)}
            done = subprocess.run([str(built.path), "-E"], cwd=tmp_path, env=env, capture_output=True, text=True,
                                  timeout=60)
            summary[name] = [line for line in done.stdout.splitlines() if "errors:" in line]
        assert summary["default"] != summary["paper"]
        for name in ("paper", "bad", "default", "paper"):  # one server: a table, another, one that fails, the first
            if name == "bad":
                code, text = server.run(f"{runner.scenario_values(problems['paper'])} | {bad}", ["-E"], 10.0)
                assert code == 2
                refused = f"overtake: the sound model's table {bad} is not this verifier's (too few numbers)"
                assert text.strip() == refused
                continue
            code, text = server.run(runner.injected(problems[name]), ["-E"], 10.0)
            assert code == 0 and [line for line in text.splitlines() if "errors:" in line] == summary[name], name
        assert server.alive()
    finally:
        server.close()


def test_the_sound_model_in_full_is_in_its_table_and_only_the_shape_in_the_verifier() -> None:
    problem = problem_for(replace(make_scenario("right", [12], [], 1), sound=Sound(profile("default"))),
                          ModelKind.FINAL)
    measured = replace(problem, scenario=replace(problem.scenario, sound=Sound(profile("default"), start_mps=3.0)))
    assert sound_model.shape_of(problem) == sound_model.shape_of(measured)
    text, other = (sound_model.table_text(sound_model.table_sound(p), p.grid) for p in (problem, measured))
    assert text != other and "measured start speed 3 m/s" in other.splitlines()[0]
    assert runner.table_file(problem) != runner.table_file(measured)


def test_a_table_damaged_in_the_cache_is_written_again(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("OVERTAKE_CACHE", str(tmp_path))
    problem = problem_for(replace(make_scenario("right", [12], [], 1), sound=Sound(profile("paper"))),
                          ModelKind.FINAL)
    path = runner.table_file(problem)
    whole = path.read_text()
    path.write_text(whole[: len(whole) // 2])
    runner.discard(tmp_path / "none")  # what a failed search does: every table is looked at again
    assert runner.table_file(problem) == path and path.read_text() == whole


@pytest.mark.parametrize(("cut", "why"), [
    (lambda t: t[: len(t) // 2], "too few numbers"),
    (lambda t: t.replace("271828", "271829"), "its end"),
    (lambda t: t + "1\n", "more after its end"),
    (lambda t: t.replace("\n", "\n99 ", 1), "another format"),
    (lambda t: "\n".join(f"2.5 {line}" if k == 2 else line for k, line in enumerate(t.split("\n"))), "another grid"),
])
def test_a_table_that_is_not_the_verifiers_is_refused_in_one_line(
        tmp_path: Path, cut: Callable[[str], str], why: str) -> None:
    """Read by hand (not through the cache): the verifier exits 2 naming the table and the reason, never a plan."""
    problem = problem_for(replace(make_scenario("right", [12], [], 1), sound=Sound(profile("paper"))),
                          ModelKind.FINAL)
    built = runner.verifier(sound_model.shape_of(problem), Strategy.SENSIBLE)
    table = tmp_path / "table.txt"
    table.write_text(cut(sound_model.table_text(sound_model.table_sound(problem), problem.grid)))
    env = {**os.environ, "OVERTAKE_SCENARIO": f"{runner.scenario_values(problem)} | {table}"}
    done = subprocess.run([str(built.path), "-E"], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert done.stderr.strip() == f"overtake: the sound model's table {table} is not this verifier's ({why})"


# -- the start, the identity check, a full road ----------------------------------------------------------------
def test_a_refused_start_has_no_successors() -> None:
    problem = problem_for(replace(make_scenario("left", [11], [], 1), sound=Sound(profile("default"))),
                          ModelKind.FINAL)
    assert sound.solve(problem, Strategy.SENSIBLE, Limits()).detail.startswith("initial state:")
    for strategy in (Strategy.SENSIBLE, Strategy.SHORTEST):
        spin = runner.search(problem, strategy)
        # the load, the probe's choice, the start: no step after
        assert spin.status is Status.NO_PLAN_WITHIN_HORIZON and spin.states_explored <= 5


def test_a_plan_that_may_end_at_the_start_is_the_empty_plan() -> None:
    problem = problem_for(replace(make_scenario("left", [], [], 0), sound=Sound(profile("default"))),
                          ModelKind.FINAL)
    ours = sound.solve(problem, Strategy.SENSIBLE, Limits())
    assert (ours.status, ours.actions) == (Status.PLAN, ())
    for strategy in (Strategy.SENSIBLE, Strategy.SHORTEST):
        spin = runner.search(problem, strategy)
        assert (spin.status, spin.actions, spin.states) == (Status.PLAN, (), ours.states)


def test_the_identity_checks_paper_cells_are_the_interpreters_only() -> None:
    speed = PAPER_GRID.speed
    zero = Bounds("zero", SpeedBounds(speed, speed), SpeedBounds(speed, speed), 0.0, False, "the identity check")
    scenario = replace(make_scenario("right", [12], [], 1), sound=Sound(zero, checks=Checks.PAPER_CELLS))
    with pytest.raises(EngineError, match="identity check"):
        runner.search(problem_for(scenario, ModelKind.FINAL), Strategy.SENSIBLE)
    with pytest.raises(EngineError, match="identity check"):
        planner.solve(scenario, Strategy.SENSIBLE, engine="spin")


def test_served_unserved_and_compiled_for_the_snapshot_give_the_same_answer() -> None:
    """The benchmark's compile-per-snapshot pipeline is the served verifier's search, compiled afresh."""
    problem = problem_for(replace(make_scenario("right", [12], [], 1), sound=Sound(profile("paper"), start_mps=13.3)),
                          ModelKind.FINAL)
    results = {"compile-once, served": runner.search(problem, Strategy.SENSIBLE),
               "compile-once": runner.search(problem, Strategy.SENSIBLE, serve=False),
               "compile-every-time": runner.search_compiling(problem, Strategy.SENSIBLE)}
    assert len({(r.status, r.actions, r.states, r.states_explored) for r in results.values()}) == 1
    assert results["compile-once, served"].status is Status.PLAN
    assert all(r.extra["spin_mode"] == mode for mode, r in results.items())


def test_more_same_direction_vehicles_than_one_word_of_followers() -> None:
    """Over 32 same-direction vehicles (sensed and phantoms): the followers take more words of the state."""
    grid = grid_for(10.5)
    left = [c for c in range(0, 80, 2) if c != grid.av_cell]
    scenario = replace(make_scenario("left", left, [], 1, horizon=12, grid=grid), sound=Sound(profile("paper")))
    problem = problem_for(scenario, ModelKind.FINAL)
    assert scenario.sound is not None
    assert sound_model.shape_of(problem).words == sound_model.full_words(grid, scenario.sound) > 1
    spin, ours = runner.search(problem, Strategy.SENSIBLE), sound.solve(problem, Strategy.SENSIBLE, Limits())
    assert ((spin.status is Status.PLAN), spin.actions) == ((ours.status is Status.PLAN), ours.actions)


def test_rendering_is_the_same_in_another_process_with_another_hash_seed() -> None:
    """The verifier cache is keyed by the rendered text: it must not depend on set or dict order in one process."""
    code = ("import sys; from dataclasses import replace; from promela import sound; from spec.assumptions import "
            "profile; from spec.models import ModelKind; from spec.scenario import make_scenario, problem_for; "
            "from spec.sound import Sound; sc = replace(make_scenario('right', [24], [], 1, cell_m=10.5), "
            "sound=Sound(profile('default'), start_mps=3.0)); "
            "p = problem_for(sc, ModelKind.PREPARATIONS); "
            "sys.stdout.write(sound.render(sound.shape_of(p)) + sound.table_text(sound.table_sound(p), p.grid))")
    texts = {subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                            env={**os.environ, "PYTHONHASHSEED": seed}).stdout for seed in ("1", "2")}
    assert len(texts) == 1 and "static SoundEarly *EARLY" in texts.pop()



@pytest.mark.parametrize("name", ["paper", "default"])
def test_measured_intervals_agree(name: str) -> None:
    """What a snapshot measured (``spec.scenario.sensed``): the engine reads each vehicle's interval from it."""
    rng, sound_ = random.Random(f"measured-{name}"), Sound(profile(name))
    for scenario in [measured_pinned(sound_), *(measured_like(rng, _draw(rng, PAPER_GRID, sound_)) for _ in range(12))]:
        for strategy in (Strategy.SENSIBLE, Strategy.SHORTEST):
            _agree(scenario, strategy)


@pytest.mark.parametrize("latency_s", sorted(AGED_SHORTEST_LENGTH))
def test_spin_plans_for_the_snapshots_age_where_it_decides_the_plan(latency_s: float) -> None:
    """Spin reads the snapshot's age (``Sound.start_error_m``, the aged phantoms) as the interpreter does: where one
    control step of age (the loop's budget) makes the shortest overtake one action longer, both answer that."""
    check_aged_witness("spin", latency_s)


# -- vehicles with their own measured speeds (spec.dynamics) -----------------------------------------------------
@settings(max_examples=80 if CI_PROFILE else 25, deadline=None)
@given(st.sampled_from(STANDARD_CELLS_M).flatmap(lambda c: sound_scenarios(Grid(c))).flatmap(with_speeds),
       st.sampled_from([Strategy.SENSIBLE, Strategy.SHORTEST]))
def test_measured_speeds_agree_with_the_interpreter(scenario: Scenario, strategy: Strategy) -> None:
    """Each measured vehicle moves by its own dynamics in Spin's C as in the interpreter: braking to a standstill,
    speeding up to its own top, its own error at the start, the minimal-risk manoeuvre braking to a stop."""
    _agree(scenario, strategy)


def test_the_measured_witnesses_agree() -> None:
    """The interpreter's pinned measured cases: a vehicle standing ahead at every cell and start speed, a follower
    faster than its lane's top, the AV beside a target that may speed up; each answered alike (a start that breaks
    the specification included)."""
    cases = [_standing_ahead(cell, start) for cell in range(11, 19) for start in (None, 3.5, 12.0)]
    cases += [_overtaking(Overtaken.PHYSICS)]
    base = measured_speeds(sensed(make_scenario("left", [9], [], 0), [(-12.0, -12.0)]), [(10.0, 10.0)])
    cases.append(replace(base, sound=sound_from(None, "paper", phantoms=False)))
    for scenario in map(_whole, cases):
        for strategy in (Strategy.SENSIBLE, Strategy.SHORTEST):
            spin = planner.solve(scenario, strategy, engine="spin")
            ours = planner.solve(scenario, strategy, engine="interpreter")
            assert (spin.status, spin.actions if strategy is Strategy.SENSIBLE else len(spin.actions)) == \
                (_within_horizon(ours.status), ours.actions if strategy is Strategy.SENSIBLE else len(ours.actions))


@pytest.mark.parametrize(("speed_mps", "latency_s", "start_mps"), [(2.3, 0.0, 1.08), (10.0, LOOP.plan_budget_s, 7.0)])
def test_the_nearest_reading_accepted_of_a_measured_vehicle_ahead_is_spins_too(
        speed_mps: float, latency_s: float, start_mps: float) -> None:
    """The interpreter's nearest accepted reading of a vehicle ahead (the start and a stop behind it proved: the empty
    plan): Spin accepts it and not a millimetre nearer, as the interpreter. At 2.3 m/s, the AV at 1.08 m/s: the vehicle
    still braking when the AV stands. At 10 m/s, above its lane's top, one control step of age: its own error at the
    plan's start (``Sound.start_error_m`` at its own top), 16 cm wider than the lane's."""
    def at(dx_m: float) -> Scenario:
        base = sensed(make_scenario("left", [11], [], 0), [(dx_m, dx_m)])
        sound_ = sound_from(None, "default", semantics="whole", latency_s=latency_s)
        return replace(measured_speeds(base, [(speed_mps, speed_mps)]), sound=replace(sound_, start_mps=start_mps))

    lo_m, hi_m = left_extent_m(11, Lane.LEFT, PAPER_GRID)
    nearest = _least_accepted_m(at, lo_m, hi_m)
    answers = {}
    for dx_m in (nearest, nearest - 1e-3):
        spin = planner.solve(at(dx_m), Strategy.SENSIBLE, engine="spin")
        ours = planner.solve(at(dx_m), Strategy.SENSIBLE, engine="interpreter")
        assert (spin.status, spin.actions) == (_within_horizon(ours.status), ours.actions)
        answers[dx_m] = (spin.status, spin.actions)
    assert answers[nearest] == (Status.PLAN, ())
    assert answers[nearest - 1e-3] != (Status.PLAN, ())


def _within_horizon(status: Status) -> Status:
    """The interpreter proves "no plan" at any horizon; Spin answers within its horizon only."""
    return Status.NO_PLAN_WITHIN_HORIZON if status is Status.NO_PLAN else status


def _whole(scenario: Scenario) -> Scenario:
    """``scenario`` under the whole-plan semantics (Spin's)."""
    assert scenario.sound is not None
    return replace(scenario, sound=replace(scenario.sound, commitment=None))


@pytest.mark.parametrize("overtaken", list(Overtaken))
def test_the_no_acceleration_profile_agrees(overtaken: Overtaken) -> None:
    """The AV beside a target measured at 3.5..6.5 m/s: under ``no-acceleration`` both complete the pass (the target
    has not sped up since the AV moved out), under physics neither does."""
    scenario = _whole(_overtaking(overtaken))
    for strategy in (Strategy.SENSIBLE, Strategy.SHORTEST):
        spin = planner.solve(scenario, strategy, engine="spin")
        ours = planner.solve(scenario, strategy, engine="interpreter")
        assert (spin.status, spin.actions if strategy is Strategy.SENSIBLE else len(spin.actions)) == \
            (_within_horizon(ours.status), ours.actions if strategy is Strategy.SENSIBLE else len(ours.actions))
        assert (spin.status is Status.PLAN) == (overtaken is Overtaken.NO_ACCELERATION)


def test_the_no_acceleration_profile_holds_a_vehicle_from_the_move_out_not_from_the_snapshot() -> None:
    """A target measured standing 126 m ahead may speed up until the AV starts its move out, two actions in: Spin's
    sensible plan passes it as the interpreter's does, not cutting in early as one held from the snapshot would."""
    scenario = replace(measured_speeds(make_scenario("left", [16], [], 1), [(0.0, 0.0)]), sound=sound_from(
        None, "default", semantics="whole", overtaken="no-acceleration", phantoms=False, sensing_error_m=1.5))
    for strategy in (Strategy.SENSIBLE, Strategy.SHORTEST):
        spin = planner.solve(scenario, strategy, engine="spin")
        ours = planner.solve(scenario, strategy, engine="interpreter")
        assert (spin.status, spin.actions) == (ours.status, ours.actions)
        assert spin.status is Status.PLAN
    assert spin.actions[:1] == (Action.RIGHT_LANE_CHANGE,)  # shortest: out at once
    sensible = planner.solve(scenario, Strategy.SENSIBLE, engine="spin").actions
    assert sensible.index(Action.RIGHT_LANE_CHANGE) == 2


@pytest.mark.parametrize(("values", "why"), [
    (lambda v: v + " 0 1", "more numbers than the scenario holds"),  # after the probe (0: the search)
    (lambda v: v[: v.rindex(" 1 ")] + " 2" + v[v.rindex(" 1 ") + 2:], "a vehicle's measured speed"),
    (lambda v: v.rsplit(" ", 1)[0], "a vehicle's measured speed"),
    (lambda v: " ".join([*v.split(" ")[:-3], "5.0", "4.0", v.split(" ")[-1]]), "a vehicle's measured speed"),
    (lambda v: v.rsplit(" ", 1)[0] + " inf", "a vehicle's measured speed"),
])
def test_a_malformed_measured_speed_is_refused_in_one_line(tmp_path: Path, values: Callable[[str], str],
                                                            why: str) -> None:
    """Injected by hand: the verifier exits 2 naming what is malformed, never a plan."""
    scenario = measured_speeds(make_scenario("left", [13], [], 1), [(6.0, 7.5)])
    problem = problem_for(replace(scenario, sound=Sound(profile("default"))), ModelKind.FINAL)
    built = runner.verifier(sound_model.shape_of(problem), Strategy.SENSIBLE)
    given_values = runner.scenario_values(problem).removesuffix(" 0")  # the probe: the plan search
    env = {**os.environ, "OVERTAKE_SCENARIO": f"{values(given_values)} 0 | {runner.table_file(problem)}"}
    done = subprocess.run([str(built.path), "-E"], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 2, (given_values, values(given_values), done.stdout[-300:])
    assert done.stderr.strip() == f"overtake: malformed OVERTAKE_SCENARIO ({why})"
