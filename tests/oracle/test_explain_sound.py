"""Explaining no plan under the sound model: which answer, the blocking vehicles and phantoms (minimal), and the
assumption to blame, each narrowed to the paper's world; under whole plans (most tests here) and under the
commitment semantics (no committed step provable, an unsafe start)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest
from click.testing import CliRunner

from ci.cli.main import cli
from oracle.explain import explain, keep_only
from oracle.planner import plan
from oracle.why import Assumption, explain_sound, keep_suspects, narrow, narrowable
from spec.answers import Status, Strategy
from spec.assumptions import Phantom
from spec.lanes import Lane
from spec.library import builtin
from spec.physical import SENSORS
from spec.safety import Conflict
from spec.scenario import Scenario, make_scenario, sensed
from spec.sound import Violation, sound_from, vehicles

ONCOMING_PHANTOM = Phantom(Lane.RIGHT, SENSORS.right_range_m, "front-right sensor's range")


def library(name: str, profile: str, **overrides: object) -> Scenario:
    """A built-in scenario under the sound model of ``profile`` (with overrides of its numbers; whole plans unless
    ``semantics`` says otherwise)."""
    entry = builtin(name)
    assert entry is not None
    overrides.setdefault("semantics", "whole")
    return replace(entry.load(), sound=sound_from(None, profile, **overrides))  # type: ignore[arg-type]


def test_keep_only_keeps_the_sound_model() -> None:
    scenario = library("paper_example", "default")
    assert keep_only(scenario, {(Lane.LEFT, 0)}).sound == scenario.sound


def test_z3_explain_refuses_the_sound_model() -> None:
    with pytest.raises(ValueError, match="sound model"):
        explain(library("one_target", "default"))


def test_removing_a_phantom_removes_it_from_the_model_and_keeps_the_others() -> None:
    scenario = library("one_target", "default")
    everything = scenario.sound.bounds.phantom_vehicles()  # type: ignore[union-attr]
    reduced = keep_suspects(scenario, [(Lane.LEFT, 0), *(p for p in everything if p != ONCOMING_PHANTOM)])
    assert reduced.sound is not None
    phantoms = [v for v in vehicles(reduced.lane, reduced.left_lane, reduced.right_lane, reduced.grid, reduced.sound)
                if v.index is None]
    assert len(phantoms) == len(everything) - 1 and all(v.lane is Lane.LEFT for v in phantoms)


def test_default_profile_blames_the_oncoming_phantom_and_the_phantoms_bound() -> None:
    result = explain_sound(library("one_target", "default"))
    assert result.status is Status.NO_PLAN and result.violation is None  # proved: every path refused or hopeless
    assert "no plan of any length" in result.answer.detail
    assert set(result.blocking) == {(Lane.LEFT, 0), ONCOMING_PHANTOM}
    assert "the oncoming phantom at +357 m" in result.name(ONCOMING_PHANTOM)
    by_assumption = {n.assumptions: n.has_plan for n in result.narrowings}
    assert by_assumption == {(a,): a is Assumption.PHANTOMS for a in Assumption}
    assert result.enough is not None and result.enough.assumptions == (Assumption.PHANTOMS,)
    assert result.everything is not None and result.everything.has_plan


@pytest.mark.parametrize(("name", "profile"), [("one_target", "default"), ("paper_example", "paper"),
                                               ("oncoming_forces_wait", "paper"), ("no_plan_boxed_in", "default")])
def test_the_blocking_set_alone_has_no_plan_and_each_removal_gives_one(name: str, profile: str) -> None:
    scenario = library(name, profile)
    result = explain_sound(scenario)
    assert result.reduced is not None and result.blocking
    assert plan(result.reduced, Strategy.SHORTEST).status is not Status.PLAN
    for suspect in result.blocking:  # checked here again, independently of explain's own check
        rest = [s for s in result.blocking if s != suspect]
        assert plan(keep_suspects(scenario, rest), Strategy.SHORTEST).status is Status.PLAN


def test_wider_same_direction_speeds_on_the_paper_profile_are_a_bound_to_blame() -> None:
    result = explain_sound(library("one_target", "paper", same="4..9"))
    assert result.status in (Status.NO_PLAN, Status.NO_PLAN_WITHIN_HORIZON) and result.violation is None
    singles = {n.assumptions[0]: n for n in result.narrowings}
    assert set(singles) == {Assumption.PHANTOMS, Assumption.SAME_SPEEDS, Assumption.ENVELOPE}  # the rest: the paper's
    narrowed = singles[Assumption.SAME_SPEEDS].answer
    assert narrowed.status is Status.PLAN  # the paper profile itself, whose plan is known
    assert narrowed.actions == plan(library("one_target", "paper"), Strategy.SHORTEST).actions


def test_an_unsafe_start_is_no_plan_naming_its_violation() -> None:
    right_ahead = make_scenario("left", [11], [], 1)
    result = explain_sound(replace(right_ahead, sound=sound_from(None, "default", semantics="whole")))
    assert result.status is Status.NO_PLAN
    assert isinstance(result.violation, Violation) and result.violation.conflict is Conflict.AHEAD
    assert (result.violation.vehicle.lane, result.violation.vehicle.index) == (Lane.LEFT, 0)
    assert result.blocking == ((Lane.LEFT, 0),)


def test_several_bounds_together_when_no_one_alone_gives_a_plan() -> None:
    scenario = library("paper_example", "default")
    result = explain_sound(scenario)
    assert not any(n.has_plan for n in result.narrowings)
    assert result.enough is not None and result.enough.has_plan and len(result.enough.assumptions) >= 2
    for left_out in result.enough.assumptions:  # minimal: without any one of them, no plan
        sound = scenario.sound
        for a in result.enough.assumptions:
            sound = narrow(sound, a) if a is not left_out else sound  # type: ignore[arg-type]
        assert plan(replace(scenario, sound=sound), Strategy.SHORTEST).status is not Status.PLAN


def test_even_the_papers_world_may_leave_no_plan() -> None:
    result = explain_sound(library("no_plan_boxed_in", "default"))
    assert result.everything is not None and not result.everything.has_plan and result.enough is None
    assert result.blocking == ((Lane.RIGHT, 0),)


def test_a_horizon_too_short_blames_no_vehicle() -> None:
    result = explain_sound(replace(make_scenario("right", [], [], 0, horizon=0),
                                   sound=sound_from(None, "default", semantics="whole")))
    assert result.status is Status.NO_PLAN_WITHIN_HORIZON and result.blocking == () and result.removals == ()


def test_a_scenario_with_a_plan_is_not_explained() -> None:
    result = explain_sound(library("one_target", "paper"))
    assert result.has_plan and result.blocking == () and result.narrowings == () and result.everything is None


def test_only_assumptions_wider_than_the_papers_world_are_narrowed() -> None:
    assert narrowable(library("one_target", "paper").sound) == (  # type: ignore[arg-type]
        Assumption.PHANTOMS, Assumption.ENVELOPE)
    assert narrowable(library("one_target", "paper", phantoms=False).sound) == (  # type: ignore[arg-type]
        Assumption.ENVELOPE,)
    assert narrowable(library("one_target", "default").sound) == tuple(Assumption)  # type: ignore[arg-type]


# -- the command ---------------------------------------------------------------------------------------------------
def explain_cli(*args: str) -> tuple[int, str]:
    done = CliRunner().invoke(cli, ["explain", *args])
    assert done.exception is None or isinstance(done.exception, SystemExit), done.exception
    return done.exit_code, done.output


def test_cli_names_the_oncoming_phantom_and_the_bound() -> None:
    code, text = explain_cli("one_target", "--bounds", "default", "--semantics", "whole")
    words = " ".join(text.split())  # the console wraps at its width
    assert code == 0 and "(no_plan):" in words and "no plan of any length" in words
    assert "the oncoming phantom at +357 m" in words
    assert "The bound to blame: phantoms" in words


def test_cli_json_under_the_sound_model() -> None:
    code, text = explain_cli("one_target", "--bounds", "default", "--semantics", "whole", "--json")
    result = json.loads(text)
    assert code == 0 and result["status"] == "no_plan" and result["violation"] is None
    assert {"kind": "phantom", "lane": "right", "index": None, "dx_m": 357.0} \
        .items() <= next(b for b in result["blocking"] if b["kind"] == "phantom").items()
    assert result["enough"]["assumptions"] == ["phantoms"] and result["sound"]["bounds"] == "default"
    assert [n["assumption"] for n in result["narrowings"]] == [a.value for a in Assumption]


def test_cli_takes_the_sound_options_and_a_files_bounds(tmp_path: Path) -> None:
    code, text = explain_cli("one_target", "--bounds", "default", "--semantics", "whole", "--no-phantoms", "--json")
    result = json.loads(text)
    assert code == 0 and all(b["kind"] == "sensed" for b in result["blocking"])
    assert "phantoms" not in [n["assumption"] for n in result["narrowings"]]
    unsafe = tmp_path / "unsafe.toml"
    unsafe.write_text('lane = "left"\nleft_lane = [11]\nright_lane = []\ntargets = 1\n[bounds]\nprofile = "default"\n'
                      'semantics = "whole"\n')
    code, text = explain_cli(str(unsafe), "--json")
    result = json.loads(text)
    assert code == 0 and result["status"] == "no_plan" and result["violation"]["conflict"] == "ahead"


def test_cli_paper_explain_keeps_its_shape() -> None:
    code, text = explain_cli("no_plan_boxed_in", "--json")
    assert code == 0 and set(json.loads(text)) == {"has_plan", "blocking", "reduced", "removals"}


# -- what the snapshot measured, and the commitment semantics -------------------------------------------------------
def test_keep_only_keeps_what_the_snapshot_measured_of_each_kept_vehicle() -> None:
    measured = sensed(make_scenario("left", [9, 12], [20], 1), ((-21.0, -20.0), (42.0, 43.0)), ((215.0, 216.0),))
    reduced = keep_only(measured, {(Lane.LEFT, 1), (Lane.RIGHT, 0)})
    assert reduced.left_lane == (12,) and reduced.left_m == ((42.0, 43.0),) and reduced.right_m == ((215.0, 216.0),)


def test_a_phantom_that_refuses_beside_a_measured_target_is_blamed_with_it() -> None:
    """A target read 25 m ahead, its cell reaching the AV's bumper: with the reading kept, the target alone leaves
    a plan and the oncoming phantom is to blame with it; the cell alone (the reading dropped) leaves none, and blamed
    the target alone on closed-loop refusals where the phantom refused."""
    scenario = replace(sensed(make_scenario("left", [11], [], 1), ((25.0, 25.0),)),
                       sound=sound_from(None, "default", semantics="whole"))
    result = explain_sound(scenario)
    assert set(result.blocking) == {(Lane.LEFT, 0), ONCOMING_PHANTOM}, result.blocking
    cells_only = replace(make_scenario("left", [11], [], 1), sound=scenario.sound)
    assert plan(keep_suspects(cells_only, [(Lane.LEFT, 0)]), Strategy.SHORTEST).status is not Status.PLAN


def test_under_the_commitment_semantics_explain_names_what_refuses_every_committed_step() -> None:
    result = explain_sound(library("prep_case_a", "default", semantics="commit"))
    assert result.status is Status.NO_PLAN and "no committed step is provable" in result.answer.detail
    assert result.blocking and all(a.status is Status.PLAN for _, a in result.removals)
    assert {w.what for w in result.parameters} == {"horizon", "cell size"}


def test_under_the_commitment_semantics_an_unsafe_start_names_its_violation_and_escape() -> None:
    code, text = explain_cli("no_plan_boxed_in", "--bounds", "default", "--json")
    result = json.loads(text)
    assert code == 0 and result["status"] in ("unsafe_start", "no_plan")
    start = make_scenario("left", [11, 17], [20], 0)
    unsafe = explain_sound(replace(start, sound=sound_from(None, "default")))
    assert unsafe.status is Status.UNSAFE_START and unsafe.violation is not None
    assert unsafe.answer.commit is not None and unsafe.answer.commit.escape is not None
