"""The mutants check themselves: each names text that occurs once, in a file of the project, and changes it; the
daily rotation reaches every mutant within its stated number of days."""

from __future__ import annotations

import argparse
import datetime
import math
import re
import subprocess
import sys
from pathlib import Path

import pytest

from ci.mutation.check import ROOT, Detector, _pytest, apply, check, main, rotation
from ci.mutation.mutants import MUTANTS, Mutant, mutant
from spec.errors import OptionError

LAYERS = {"spec", "oracle", "promela", "sim", "ci"}


@pytest.mark.parametrize("m", MUTANTS, ids=lambda m: m.name)
def test_each_mutant_changes_text_that_occurs_once_in_the_project(m: Mutant, tmp_path: Path) -> None:
    source = ROOT / m.path
    assert m.path.split("/")[0] in LAYERS and source.read_text().count(m.old) == 1 and m.old != m.new
    (tmp_path / m.path).parent.mkdir(parents=True)
    (tmp_path / m.path).write_text(source.read_text())
    apply(m, tmp_path)
    assert (tmp_path / m.path).read_text() != source.read_text()


def test_there_are_mutants_in_every_engine_spec_the_discretiser_and_the_simulator() -> None:
    files = {m.path for m in MUTANTS}
    assert len(MUTANTS) >= 15 and len({m.name for m in MUTANTS}) == len(MUTANTS)
    for needed in ("promela/render.py", "oracle/bmc.py", "oracle/interpreter.py", "spec/models.py", "spec/cells.py",
                   "sim/simulator.py", "sim/traffic.py", "sim/tolerance.py", "promela/sound.py", "oracle/bmc_sound.py",
                   "spec/sound.py"):
        assert needed in files


@pytest.mark.parametrize("per_day", [1, 3, 5])
def test_the_rotation_reaches_every_mutant_within_its_days(per_day: int) -> None:
    days = math.ceil(len(MUTANTS) / per_day)
    start = datetime.date(2026, 11, 23)
    seen = {m.name for d in range(days) for m in rotation(per_day, start + datetime.timedelta(days=d))}
    assert seen == {m.name for m in MUTANTS}


def test_cis_daily_share_reaches_every_mutant_within_a_week() -> None:
    """``.ci/run`` checks ``--rotate K`` mutants a day: K must grow with the mutants so that a week sees them all."""
    found = re.search(r"ci\.mutation\.check --rotate (\d+)", (ROOT / ".ci" / "run").read_text())
    assert found is not None
    assert math.ceil(len(MUTANTS) / int(found.group(1))) <= 7


def test_count_checks_the_first_of_those_chosen() -> None:
    from ci.mutation.check import _chosen

    args = argparse.Namespace(mutants=None, rotate=2, date="2026-11-23", count=1)
    assert [m.name for m in _chosen(args)] == [rotation(2, datetime.date(2026, 11, 23))[0].name]
    everything = argparse.Namespace(mutants=None, rotate=None, date=None, count=3)
    assert [m.name for m in _chosen(everything)] == [m.name for m in MUTANTS[:3]]


def test_bad_mutation_input_is_exit_two(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--mutants", "no-such-mutant"]) == 2
    assert main(["--rotate", "0"]) == 2
    assert main(["--rotate", "2", "--date", "23/11/2026"]) == 2
    assert main(["--count", "0"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 4 and "no-such-mutant" in lines[0] and "--date" in lines[2] and "--count" in lines[-1]
    with pytest.raises(OptionError):
        mutant("nope")


@pytest.mark.parametrize(("body", "caught"), [
    ("def test_a():\n    assert 0\n\ndef test_b():\n    pass\n", True),  # xdist stops at the failure: exit 2
    ("import no_such_module_here\n\ndef test_a():\n    pass\n", False),  # a collection error is no catch
])
def test_a_test_detector_on_every_core_catches_a_failure_and_not_a_module_that_does_not_import(
        body: str, caught: bool, tmp_path: Path) -> None:
    """The detector's own command on a planted file: pytest-xdist's stop at the first failure, as it prints it."""
    (tmp_path / "test_planted.py").write_text(body)
    detector = Detector("planted", lambda m, work: _pytest(str(tmp_path / "test_planted.py")), (1,), tests=True)
    done = subprocess.run(detector.command(MUTANTS[0], tmp_path), cwd=tmp_path, capture_output=True, text=True,
                          timeout=120)
    assert detector.caught(done) is caught, done.stdout[-500:]


@pytest.mark.parametrize(("code", "summary", "caught"), [
    (2, "ERROR t.py::test_a - RuntimeError\n!!! stopping after 1 failures !!!", True),  # a fixture's error
    (1, "FAILED t.py::test_a - assert 0", True),  # pytest on one core
    (0, "1 passed", False),
    (2, "FAILED t.py::test_a - assert 0\n!!! Interrupted: 1 error during collection !!!", False),  # not xdist's stop
])
def test_what_a_test_detector_counts_as_a_catch(code: int, summary: str, caught: bool) -> None:
    detector = Detector("planted", lambda m, work: _pytest("t.py"), (1,), tests=True)
    done = subprocess.CompletedProcess(["pytest"], code, stdout=summary, stderr="")
    assert detector.caught(done) is caught


def test_the_first_detector_runs_the_tests_that_mirror_the_mutated_module() -> None:
    from ci.mutation.check import DETECTORS, _module_tests

    assert _module_tests(mutant("commit-one-action-past-its-escape")) == ["tests/spec/test_commitment.py",
                                                                          "tests/oracle/test_commit.py"]
    assert _module_tests(mutant("spec-oncoming-odds-first-two-swapped")) == ["tests/sim/test_spawn_odds.py"]
    assert all((ROOT / t).is_file() for m in MUTANTS for t in m.tests)
    assert "tests/sim/test_safety_by_hand.py" in _module_tests(mutant("safety-closing-reversed"))
    unmirrored = Mutant("x", "sim/simulator.py", "a", "b", "no test file mirrors sim/simulator.py")
    assert DETECTORS[0].command(unmirrored, Path(".")) == []


def _exits(code: int) -> Detector:
    return Detector(f"exits {code}", lambda m, work: [sys.executable, "-c", f"import sys; sys.exit({code})"], (6,))


def test_a_detector_that_crashes_catches_nothing_and_the_next_one_is_tried(tmp_path: Path) -> None:
    """A crash (here exit 5: a collection error, bad input, a missing file would do the same) is no verdict: a later
    detector may catch the mutant; when none does, the mutant has none either (neither caught nor survived)."""
    caught = check(MUTANTS[0], tmp_path, detectors=(_exits(5), _exits(6)))
    assert caught.caught_by == "exits 6" and any("exits 5: crashed, exit 5" in e for e in caught.errors)
    undecided = check(MUTANTS[0], tmp_path, detectors=(_exits(5), _exits(0)))
    assert undecided.caught_by is None and undecided.undecided and "NO VERDICT" in undecided.outcome()
    survived = check(MUTANTS[0], tmp_path, detectors=(_exits(0),))
    assert survived.caught_by is None and not survived.undecided and survived.outcome() == "SURVIVED"
