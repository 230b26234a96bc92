"""The CLI: JSON shapes, exit codes, and one clear line for every kind of bad input."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click
import pytest

from ci.cli import main as entry
from spec.errors import ExitCode
from spec.library import builtin
from tests.conftest import run_cli as run


def write(tmp_path: Path, name: str, text: str) -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_plan_json_shape_and_exit_zero() -> None:
    done = run("plan", str(builtin("one_target").path), "--json", "--strategy", "shortest")  # type: ignore[union-attr]
    assert done.returncode == 0, done.stderr
    answer = json.loads(done.stdout)
    assert set(answer) >= {"status", "model", "engine", "strategy", "actions", "states", "stats"}
    assert answer["status"] == "plan" and answer["engine"] == "interpreter"
    assert answer["actions"] == ["accelerate", "right_lane_change", "accelerate", "accelerate", "left_lane_change"]
    assert len(answer["states"]) == 6 and set(answer["stats"]) == {"states_explored", "elapsed_ms"}


def test_plan_for_people_draws_both_lanes() -> None:
    done = run("plan", "paper_example")
    assert done.returncode == 0 and "step 7: left_lane_change" in done.stdout and "right" in done.stdout


@pytest.mark.parametrize(("name", "code", "status"), [
    ("no_plan_boxed_in", 1, "no_plan"), ("no_plan_within_horizon", 1, "no_plan_within_horizon")])
def test_plan_exit_one_without_a_plan(name: str, code: int, status: str) -> None:
    done = run("plan", name, "--json")
    assert done.returncode == code and json.loads(done.stdout)["status"] == status


def test_plan_exit_three_when_a_limit_is_hit() -> None:
    done = run("plan", "three_targets", "--max-states", "5", "--json")
    answer = json.loads(done.stdout)
    assert done.returncode == 3 and answer["status"] == "incomplete" and "state limit 5" in answer["detail"]
    assert answer["actions"] == []


def test_validate_valid_and_invalid(tmp_path: Path) -> None:
    path = write(tmp_path, "s.json", '{"lane": "left", "left_lane": [12], "right_lane": [], "targets": 1}')
    ok = run("validate", path, "--actions", "accelerate,right_lane_change,accelerate,accelerate,left_lane_change",
             "--json")
    assert ok.returncode == 0 and json.loads(ok.stdout)["valid"] is True
    bad = run("validate", path, "--actions", "accelerate,accelerate", "--json")
    verdict = json.loads(bad.stdout)
    assert bad.returncode == 1 and verdict["valid"] is False and "collision" in verdict["reason"]
    assert len(verdict["states"]) == 2


BAD_FILES = [
    ("unknown.json", '{"lane": "left", "left_lane": [], "right_lane": [], "speed": 3}', "speed", "unknown key"),
    ("type.json", '{"lane": "left", "left_lane": "12", "right_lane": []}', "left_lane", "must be a list"),
    ("celltype.json", '{"lane": "left", "left_lane": [1.5], "right_lane": []}', "left_lane[0]", "integer"),
    ("range.toml", 'lane = "left"\nleft_lane = [51]\nright_lane = []', "left_lane[0]", "outside"),
    ("negative.toml", 'lane = "left"\nleft_lane = []\nright_lane = [-1]', "right_lane[0]", "outside"),
    ("dup.json", '{"lane": "left", "left_lane": [12, 12], "right_lane": []}', "left_lane[1]", "two vehicles"),
    ("crash.json", '{"lane": "left", "left_lane": [10], "right_lane": []}', "left_lane[0]", "initial collision"),
    ("crash_r.json", '{"lane": "right", "left_lane": [], "right_lane": [10]}', "right_lane[0]", "initial collision"),
    ("targets.json", '{"lane": "left", "left_lane": [5, 12], "right_lane": [], "targets": 2}', "targets",
     "only 1"),
    ("lane.json", '{"lane": "middle", "left_lane": [], "right_lane": []}', "lane", "must be one of"),
    ("model.json", '{"lane": "left", "left_lane": [], "right_lane": [], "model": "x"}', "model", "must be one of"),
    ("horizon.json", '{"lane": "left", "left_lane": [], "right_lane": [], "horizon": -1}', "horizon", "between"),
    ("missing.json", '{"lane": "left", "left_lane": []}', "right_lane", "missing"),
    ("malformed.json", '{"lane": "left",', "file", "malformed JSON"),
    ("malformed.toml", 'lane = "left\n', "file", "malformed TOML"),
    ("array.json", "[1, 2]", "file", "top level"),
    ("binary.json", "\udcff", "file", "UTF-8"),
    ("scenario.yaml", "lane: left", "file", "unknown format"),
]


@pytest.mark.parametrize(("name", "text", "key", "reason"), BAD_FILES, ids=[b[0] for b in BAD_FILES])
@pytest.mark.parametrize("command", ["plan", "validate"])
def test_bad_input_is_one_line_exit_two(tmp_path: Path, name: str, text: str, key: str, reason: str,
                                        command: str) -> None:
    path = tmp_path / name
    path.write_bytes(text.encode("utf-8", "surrogateescape"))
    extra = ["--actions", "drive"] if command == "validate" else []
    done = run(command, str(path), *extra)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert str(path) in lines[0] and key in lines[0] and reason in lines[0]
    assert "Traceback" not in done.stderr


def test_missing_file_and_unknown_action_and_engine(tmp_path: Path) -> None:
    for args, needle in [
        (("plan", str(tmp_path / "nope.json")), "no such file"),
        (("validate", "one_target", "--actions", "fly"), "unknown action 'fly'"),
        (("plan", "one_target", "--engine", "quantum"), "unknown engine"),
        (("plan", "one_target", "--horizon", "9999"), "--horizon"),
        (("plan", "one_target", "--strategy", "fastest"), "--strategy"),
        (("plan", "one_target", "--max-states", "0"), "--max-states"),
        (("plan",), "Missing argument"),
        (("fly",), "No such command"),
    ]:
        done = run(*args)
        assert done.returncode == 2 and needle in done.stderr and len(done.stderr.strip().splitlines()) == 1


def test_unreadable_file_is_bad_input(tmp_path: Path) -> None:
    folder = tmp_path / "scenario.json"
    folder.mkdir()  # exists, has the right suffix, but cannot be read as a file
    done = run("plan", str(folder))
    assert done.returncode == 2 and "not a regular file" in done.stderr and str(folder) in done.stderr


def test_demo_runs_every_builtin_and_matches_expectations() -> None:
    done = run("demo", "--engine", "interpreter")
    assert done.returncode == 0, done.stdout + done.stderr
    assert "all answers as expected" in done.stdout


def test_scenarios_lists_the_library_with_expectations() -> None:
    done = run("scenarios", "--json")
    listed = {s["name"]: s for s in json.loads(done.stdout)}
    assert done.returncode == 0 and listed["prep_case_a"]["model"] == "preparations"
    assert all(Path(s["path"]).exists() for s in listed.values())


def test_engines_lists_every_registered_engine() -> None:
    done = run("engines")
    assert done.returncode == 0 and all(name in done.stdout for name in ("interpreter", "spin", "z3"))


def test_plan_engine_all_json() -> None:
    done = run("plan", "one_target", "--engine", "all", "--json")
    result = json.loads(done.stdout)
    assert done.returncode == 0 and result["agree"] is True and result["disagreements"] == []
    assert {a["engine"] for a in result["answers"]} >= {"interpreter"}


def test_plan_on_a_finer_grid_from_the_file_or_the_option(tmp_path: Path) -> None:
    named = write(tmp_path, "fine.toml", 'lane = "left"\nleft_lane = [24]\nright_lane = []\ntargets = 1\ncell_m = 10.5')
    plain = write(tmp_path, "plain.toml", 'lane = "left"\nleft_lane = [24]\nright_lane = []\ntargets = 1')
    by_file = json.loads(run("plan", named, "--json", "--strategy", "shortest").stdout)
    by_option = json.loads(run("plan", plain, "--cell-m", "10.5", "--json", "--strategy", "shortest").stdout)
    assert by_file["actions"] == by_option["actions"] and by_file["status"] == "plan"
    assert by_file["states"][0]["left_lane"] == [24]
    for clash in (run("plan", named, "--cell-m", "7"), run("plan", "paper_example", "--cell-m", "10.5")):
        assert clash.returncode == 2 and "--cell-m" in clash.stderr and "its own grid" in clash.stderr
        assert len(clash.stderr.strip().splitlines()) == 1
    odd = run("plan", plain, "--cell-m", "10")
    assert odd.returncode == 2 and "not a whole number" in odd.stderr and len(odd.stderr.strip().splitlines()) == 1


def test_an_end_of_file_inside_a_command_is_an_internal_error_not_an_interrupt(
        monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    """click turns every EOFError into its Abort, which reads as Ctrl-C; a closed pipe (a helper process that died)
    must say what it was and exit 5."""
    @click.command("broken")
    def broken() -> None:
        raise EOFError("the pipe closed")

    monkeypatch.setitem(entry.cli.commands, "broken", broken)
    monkeypatch.setattr(sys, "argv", ["overtake", "broken"])
    monkeypatch.delenv("OVERTAKE_DEBUG", raising=False)
    with pytest.raises(SystemExit) as ended:
        entry.main()
    err = capsys.readouterr().err
    assert ended.value.code == ExitCode.ENGINE_FAILED, err
    assert "internal error: EOFError: the pipe closed" in err and "interrupted" not in err
