"""Hostile input, command by command: every case is exit 2 with one line naming the option or file, never a
traceback, a hang or a run that starts.

Cases are built per command from the kinds of input it accepts (numbers, whole numbers, names, outputs, scenario
files). Each command starts from a cheap valid invocation (``BASE``) with one bad value appended (the last value of an
option wins), so a bad value wrongly accepted does a few milliseconds of work and then fails the test, instead of
starting a campaign. Every case runs in a folder of its own holding the hostile files (``_hostile_files``), and the
ones that read a scenario file run under a memory ceiling, so a file read without bound fails the test instead of
eating the machine. The cases run in processes forked from a server that has done the imports once (``_serve``);
a sample runs again in fresh processes, as a user starts them.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import resource
import runpy
import signal
import subprocess
import sys
import time
import traceback
import warnings
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any, NamedTuple

import click
import pytest

from ci.cli.crossval import DEFAULT_SPACE
from ci.cli.main import cli
from ci.conformance.conform import COUNT
from ci.shared.options import CHECK_COUNT, FRAMED, HORIZON, MAX_STATES, PER_RUN, REPRODUCERS, RUNS, SEED, WORKERS
from spec.errors import ExitCode
from spec.grid import PAPER_GRID

pytestmark = pytest.mark.xdist_group("bad-input")  # on one worker: one fork server and one measured ceiling

ROOT = Path(__file__).resolve().parents[3]  # the checkout under test, whatever is installed
QUICK_S = 10.0  # bad input is refused before any work: a case that takes longer started some, or hung
HEADROOM = 256 * 2**20  # address space a scenario-reading command may use above what its imports take


class Case(NamedTuple):
    """One hostile invocation: its arguments, what its one line must name, and its exit code."""

    args: tuple[str, ...]
    named: str
    code: int = ExitCode.BAD_INPUT
    module: str = "ci.cli.main"
    ceiling: bool = False  # under a memory ceiling (it reads a scenario file)
    env: tuple[tuple[str, str], ...] = ()  # set in the case's environment

    @property
    def id(self) -> str:
        prefix = "conform " if self.module == "ci.conformance.conform" else ""
        return prefix + " ".join(self.args)


# A cheap valid invocation of every command: what a wrongly accepted bad value would run.
SPACE = "left=0@9..9,right=0@12..12,lanes=left"
BASE: dict[str, tuple[str, ...]] = {
    "plan": ("plan", "one_target"),
    "validate": ("validate", "one_target", "--actions", "drive"),
    "promela": ("promela", "one_target", "--model", "final"),
    "explain": ("explain", "one_target"),
    "shrink": ("shrink", "one_target", "--engine", "interpreter", "--engine", "z3", "--strategy", "shortest"),
    "demo": ("demo", "--engine", "interpreter"),
    "engines": ("engines",),
    "scenarios": ("scenarios",),
    "simulate": ("simulate", "--km", "0.01", "--out", "sim"),
    "audit": ("audit", "--km", "0.01", "--runs", "1", "--cells", "21", "--traffic", "paper", "--sensing", "exact",
              "--engines", "interpreter", "--snapshots", "0", "--opportunity-checks", "0", "--workers", "1",
              "--out", "audit"),
    "crossval": ("crossval", "--source", "exhaustive", "--space", SPACE, "--properties", "existence", "--engines",
                 "interpreter", "--workers", "1", "--out", "crossval"),
    "conform": ("--count", "1", "--engines", "interpreter,z3", "--strategy", "shortest", "--out", "conform"),
    "report": ("report", "report_in", "--out", "report.html"),
}

NOT_NUMBERS = ("nan", "inf", "-inf", "1e308", "-1", "ten")


def _case(command: str, *extra: str, named: str, code: int = ExitCode.BAD_INPUT,
          env: tuple[tuple[str, str], ...] = ()) -> Case:
    module = "ci.conformance.conform" if command == "conform" else "ci.cli.main"
    return Case((*BASE[command], *extra), named, code, module, env=env)


NO_TOOLS = (("PATH", "/nonexistent"),)  # spin and gcc are not installed


def vehicle_speeds(command: str) -> list[Case]:
    """``--vehicle-speeds``: an unknown source; measured speeds without tracking, from an engine that moves every
    vehicle at its lane's speeds, or (simulate) for the paper's rules; ``--overtaken``: an unknown profile, or one
    without measured speeds: exit 2 naming it."""
    measured = ("--vehicle-speeds=measured",)
    return [*choices(command, "--vehicle-speeds"), _case(command, *measured, named="--vehicle-speeds"),
            _case(command, *measured, "--tracking=on", "--engine=z3", named="--vehicle-speeds"),
            *([_case(command, *measured, "--tracking=on", named="--vehicle-speeds")] if command == "simulate" else []),
            # the no-acceleration profile speaks of measured vehicles: lane speeds are refused
            *choices(command, "--overtaken"), _case(command, "--overtaken=no-acceleration", named="--overtaken")]


def faults(command: str) -> list[Case]:
    """Unknown fault kinds, rates outside [0, 1], persistences below one sweep, a bad steering offset: exit 2."""
    bad = ("fake=0.1", "fake-gap", "fake-gap=1.5", "fake-gap=-0.1", "fake-gap=nan", "fake-gap=x", "fake-gap=0.1/0",
           "fake-gap=0.1/-2", "fake-gap=0.1/2.5", "split=0.1,split=0.2")
    return [*(_case(command, f"--faults={value}", named="--faults") for value in bad), *choices(command, "--tracking"),
            *(_case(command, f"--steering-offset-deg={value}", named="--steering-offset-deg")
              for value in ("nan", "inf", "-1", "91", "x"))]


def no_spin(command: str, *extra: str) -> Case:
    """An engine whose tools are missing is exit 4 naming the tool, before any work."""
    return _case(command, *extra, named="spin", code=ExitCode.TOOL_MISSING, env=NO_TOOLS)


def numbers(command: str, *options: str) -> list[Case]:
    """Every numeric option refuses what is not a finite number in its range."""
    return [_case(command, f"{option}={value}", named=option) for option in options for value in NOT_NUMBERS]


def whole(command: str, option: str, kind: click.IntRange) -> list[Case]:
    """A whole-number option refuses a value below and above its range, a fraction and text."""
    assert kind.min is not None and kind.max is not None, f"{option} has no stated bounds"
    return [_case(command, f"{option}={value}", named=option)
            for value in (kind.min - 1, kind.max + 1, 10**30, 1.5, "many")]


def choices(command: str, option: str, *, lists: bool = False) -> list[Case]:
    """A name option refuses an unknown name and no name at all (a list option: also a list of nothing)."""
    bad = ["nosuch", ""] + ([",", "nosuch,"] if lists else [])
    return [_case(command, f"{option}={value}", named=option) for value in bad]


BAD_SPEEDS = ("9..5", "nan..9", "1..inf", "-1..3", "ten", "1..2..3", "..4", "")


def sound(command: str) -> list[Case]:
    """The sound model's options (``sound_options``), and a scenario file's bounds table gone wrong."""
    return [*sound_options(command), *(Case((BASE[command][0], name, *BASE[command][2:]), key, ceiling=True)
                                       for name, key in BOUNDS_FILES.items())]


def sound_options(command: str, *extra: str, commitment: bool = True) -> list[Case]:
    """The sound model's options: an unknown profile, speed intervals that are not intervals of finite speeds,
    numbers out of range (a sensing error beyond the window, a latency above half a second, an acceleration bound of
    0 or below), and (``commitment``:
    where the command takes them) the commitment semantics'; ``extra`` arguments with each."""
    return [*(_case(command, *extra, f"--bounds={value}", named="--bounds") for value in ("nosuch", "")),
            *(_case(command, *extra, f"{option}={value}", named=option) for option in ("--sensing-error-m",
                                                                                        "--av-speed-mps",
                                                                                        "--oncoming-view-m",
                                                                                        "--latency-s")
              for value in NOT_NUMBERS),
            _case(command, *extra, "--latency-s=0.6", named="--latency-s"),  # an older snapshot is not planned from
            *(_case(command, *extra, f"--oncoming-view-m={value}", named="--oncoming-view-m")
              for value in ("0", "400")),  # the view starts past the AV's front and ends within the sensor's range
            *(_case(command, *extra, f"{option}={value}", named=option) for option in ("--same-mps", "--oncoming-mps")
              for value in BAD_SPEEDS),
            _case(command, *extra, "--sensing-error-m=1001", named="--sensing-error-m"),
            *(_case(command, *extra, f"{option}={value}", named=option) for option in ("--accel-mps2", "--brake-mps2")
              for value in (*NOT_NUMBERS, "0", "-3")),  # an acceleration bound is above 0
            *(_case(command, *extra, f"--overtaken={value}", named="--overtaken")
              for value in ("sometimes", "", "PHYSICS ")),  # one of the profiles, spelt as stated
            *(_case(command, *extra, f"--sideways-s={value}", named="--sideways-s")
              for value in (*NOT_NUMBERS, "-0.5", "2.5")),  # a move takes at most its 2 s
            *(_case(command, *extra, f"--sensors-ahead-m={value}", named="--sensors-ahead-m")
              for value in ("nan", "inf", "1e308", "ten", "-1.6", "1.6")),  # within the envelope's 1.5 m either way
            *(commitment_options(command, *extra) if commitment else ())]


def commitment_options(command: str, *extra: str) -> list[Case]:
    """The commitment semantics' options: an unknown semantics, a commitment of no action or past the longest
    horizon, escapes unknown, given twice or none, and either with whole plans."""
    return [*(_case(command, *extra, f"--semantics={value}", named="--semantics") for value in ("partial", "")),
            *(_case(command, *extra, f"--commit-max={value}", named="--commit-max")
              for value in ("0", "-1", "201", "1.5", "many", "")),
            *(_case(command, *extra, f"--escapes={value}", named="--escapes")
              for value in ("teleport", "abort,abort", "", ",")),
            _case(command, *extra, "--semantics=whole", "--commit-max=2", named="--commit-max")]


#: Scenario files whose ``bounds`` table is wrong, and the key each one's line must name.
BOUNDS_FILES = {"bounds_reversed.toml": "bounds.same_mps", "bounds_key.json": "bounds.speed",
                "bounds_nan.json": "bounds.sensing_error_m", "bounds_profile.toml": "bounds.profile",
                "bounds_list.json": "bounds", "bounds_phantoms.toml": "bounds.phantoms",
                "bounds_view.toml": "bounds.oncoming_view_m", "bounds_latency.toml": "bounds.latency_s",
                "bounds_commit.toml": "bounds.commit_max", "bounds_escapes.json": "bounds.escapes",
                "bounds_semantics.toml": "bounds.semantics", "bounds_accel.toml": "bounds.accel_mps2",
                "bounds_brake.json": "bounds.brake_mps2", "speeds_length.json": "left_mps",
                "speeds_reversed.toml": "left_mps[0]", "speeds_negative.json": "left_mps[0]",
                "speeds_nan.json": "right_mps[0]", "bounds_overtaken.toml": "bounds.overtaken",
                "bounds_sideways.toml": "bounds.sideways_s", "bounds_sensors_ahead.json": "bounds.sensors_ahead_m",
                "bounds_sensed_sets.toml": "bounds.sensed_sets",
                "bounds_from_reference.json": "bounds.from_reference"}


def out_dirs(command: str, option: str = "--out") -> list[Case]:
    """An output folder refuses a file, a folder that cannot be made, and places nobody may write."""
    return [_case(command, f"{option}={value}", named=option)
            for value in ("a_file", "a_file/sub", "/proc/overtake", "/sys/overtake", "/dev/null")]


def out_files(command: str, option: str = "--out") -> list[Case]:
    """An output file refuses a folder, a missing folder, and places nobody may write."""
    return [_case(command, f"{option}={value}", named=option)
            for value in ("a_folder", "missing/out.txt", "a_file/out.txt", "/proc/out.txt", "/sys/out.txt")]


def schedulers(command: str) -> list[Case]:
    """A scheduler without --executor dask, and addresses dask cannot read."""
    return [_case(command, *extra, f"--scheduler={value}", named="--scheduler")
            for extra, value in (((), "tcp://127.0.0.1:8786"), (("--executor=dask",), "nonsense"),
                                 (("--executor=dask",), "tcp://host"), (("--executor=dask",), "ftp://host:21"))]


def unknown(command: str) -> list[Case]:
    """An option the command does not have, and an argument it does not take."""
    return [_case(command, "--bogus", named="--bogus"), _case(command, "stray", named="stray")]


# Scenario files that are not scenarios: each name is made in the case's folder by ``_hostile_files``.
SCENARIO_FILES = ("missing.json", "folder.json", "/dev/zero", "/dev/urandom", "zero.json", "urandom.toml",
                  "fifo.json", "huge.json", "binary.json", "duplicate.json", "malformed.json", "malformed.toml",
                  "list.json", "unknown_key.toml", "far_cell.json", "negative_cell.toml", "nan_cell.json",
                  "nan_grid.toml", "nan_horizon.json", "too_many_targets.toml", "no_lane.json", "plan.txt",
                  "deep.json", "deep.toml", "digits.json", "digits.toml", "long_string.json", "long_key.toml")


def scenario_files(command: str) -> list[Case]:
    """Every scenario-file argument refuses each hostile file, naming it."""
    base = BASE[command]
    return [Case((base[0], name, *base[2:]), name, ceiling=True) for name in SCENARIO_FILES]


def _hostile_files(folder: Path) -> None:
    (folder / "a_file").write_text("")
    (folder / "a_folder").mkdir()
    (folder / "folder.json").mkdir()
    (folder / "zero.json").symlink_to("/dev/zero")
    (folder / "urandom.toml").symlink_to("/dev/urandom")
    os.mkfifo(folder / "fifo.json")
    good = '"lane": "left", "left_lane": [12], "right_lane": []'
    files = {
        "huge.json": "{" + good + ', "targets": 1' + " " * 300_000 + "}",
        "duplicate.json": "{" + good + ', "lane": "right"}',
        "malformed.json": '{"lane": "left", "left_lane": [12',
        "malformed.toml": 'lane = "left"\nleft_lane = [12',
        "list.json": "[" + good.replace(":", ",") + "]",
        "unknown_key.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\nspeed = 3\n',
        "far_cell.json": '{"lane": "left", "left_lane": [999], "right_lane": []}',
        "negative_cell.toml": 'lane = "left"\nleft_lane = [-3]\nright_lane = []\n',
        "nan_cell.json": '{"lane": "left", "left_lane": [NaN], "right_lane": []}',
        "nan_grid.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\ncell_m = nan\n',
        "nan_horizon.json": "{" + good + ', "horizon": NaN}',
        "too_many_targets.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\ntargets = 3\n',
        "no_lane.json": '{"left_lane": [12], "right_lane": []}',
        "plan.txt": "lane = left\n",
        "deep.json": '{"lane": ' + "[" * 50_000 + "]" * 50_000 + "}",
        "deep.toml": "lane = " + "[" * 50_000 + "]" * 50_000 + "\n",
        "digits.json": '{"lane": "left", "left_lane": [' + "9" * 5000 + '], "right_lane": []}',
        "digits.toml": 'lane = "left"\nleft_lane = [' + "9" * 5000 + "]\nright_lane = []\n",
        "long_string.json": '{"lane": "' + "x" * 200_000 + '", "left_lane": [], "right_lane": []}',
        "long_key.toml": "k" * 200_000 + ' = 1\nlane = "left"\nleft_lane = []\nright_lane = []\n',
        "bounds_reversed.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\n[bounds]\nsame_mps = [9, 5]\n',
        "bounds_key.json": "{" + good + ', "bounds": {"speed": 3}}',
        "bounds_nan.json": "{" + good + ', "bounds": {"sensing_error_m": NaN}}',
        "bounds_profile.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\n[bounds]\nprofile = "psychic"\n',
        "bounds_list.json": "{" + good + ', "bounds": [1, 2]}',
        "bounds_phantoms.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\n[bounds]\nphantoms = "yes"\n',
        "bounds_view.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\n[bounds]\noncoming_view_m = 400\n',
        "bounds_latency.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\n[bounds]\nlatency_s = -0.1\n',
        "bounds_commit.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\n[bounds]\ncommit_max = 0\n',
        "bounds_escapes.json": '{"lane": "left", "left_lane": [12], "right_lane": [], "bounds": {"escapes": []}}',
        "bounds_semantics.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\n[bounds]\nsemantics = 3\n',
        "bounds_accel.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\n[bounds]\naccel_mps2 = 0\n',
        "bounds_brake.json": "{" + good + ', "bounds": {"brake_mps2": -9}}',
        "bounds_overtaken.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\n[bounds]\novertaken = true\n',
        "bounds_sideways.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\n[bounds]\nsideways_s = 3\n',
        "bounds_sensors_ahead.json": "{" + good + ', "bounds": {"sensors_ahead_m": -2}}',
        "bounds_from_reference.json": "{" + good + ', "bounds": {"from_reference": 1}}',
        "bounds_sensed_sets.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\n[bounds]\nsensed_sets = "yes"\n',
        "speeds_length.json": "{" + good + ', "left_mps": [[5, 6], [7, 8]], "bounds": {}}',
        "speeds_reversed.toml": 'lane = "left"\nleft_lane = [12]\nright_lane = []\nleft_mps = [[6, 5]]\n[bounds]\n',
        "speeds_negative.json": "{" + good + ', "left_mps": [[-1, 5]], "bounds": {}}',
        "speeds_nan.json": '{"lane": "left", "left_lane": [], "right_lane": [30], "right_mps": [[NaN, 5]]}',
    }
    for name, text in files.items():
        (folder / name).write_text(text)
    (folder / "binary.json").write_bytes(bytes(range(256)) * 4)
    for name in ("report_in", "report_zero", "report_fifo", "report_malformed"):
        (folder / name).mkdir()
    (folder / "report_in" / "mutation.json").write_text(
        '[{"mutant": "m", "caught_by": "tests", "seconds": 1.0, "reproducer": "", "errors": []}]')
    (folder / "report_zero" / "summary.json").symlink_to("/dev/zero")
    os.mkfifo(folder / "report_fifo" / "audit.json")
    (folder / "report_malformed" / "audit.json").write_text('{"settings": {')


CASES: list[Case] = [
    # plan
    *numbers("plan", "--timeout", "--cell-m"),
    *whole("plan", "--horizon", HORIZON),
    *whole("plan", "--max-states", MAX_STATES),
    *choices("plan", "--strategy"), *choices("plan", "--model"), *choices("plan", "--engine"),
    _case("plan", "--engine", "z3", "--timeout", "1e308", named="--timeout"),
    _case("plan", "--cell-m=13", named="--cell-m"),
    _case("plan", "--engine=z3", "--strategy=sensible", named="--strategy"),
    no_spin("plan", "--engine=spin"), no_spin("plan", "--engine=all"),
    *unknown("plan"), *scenario_files("plan"),
    *sound("plan"), _case("plan", "--bounds=default", "--engine=z3", "--strategy=sensible", named="--strategy"),
    # validate
    *numbers("validate", "--cell-m"), *whole("validate", "--horizon", HORIZON), *choices("validate", "--model"),
    *(_case("validate", f"--actions={value}", named="--actions") for value in ("fly", ",,", "drive,,drive", ",drive")),
    *unknown("validate"), *scenario_files("validate"), *sound("validate"),
    # promela
    *numbers("promela", "--cell-m"), *whole("promela", "--horizon", HORIZON), *choices("promela", "--model"),
    *out_files("promela"), *unknown("promela"), *scenario_files("promela"),
    # explain
    *numbers("explain", "--cell-m"), *unknown("explain"), *scenario_files("explain"),
    *sound("explain"),
    # shrink
    *numbers("shrink", "--cell-m"), *choices("shrink", "--strategy"), *choices("shrink", "--engine"),
    *out_files("shrink"), *unknown("shrink"), *scenario_files("shrink"), no_spin("shrink", "--engine=spin"),
    # demo, engines, scenarios
    *choices("demo", "--strategy"), *choices("demo", "--engine"), *unknown("demo"), no_spin("demo", "--engine=spin"),
    *unknown("engines"), *unknown("scenarios"),
    # simulate
    *numbers("simulate", "--km", "--cell-m", "--step-tolerance", "--plan-tolerance"),
    *whole("simulate", "--seed", SEED), *whole("simulate", "--runs", RUNS),
    *whole("simulate", "--workers", WORKERS),
    *choices("simulate", "--engine"), *choices("simulate", "--strategy"), *choices("simulate", "--executor"),
    *choices("simulate", "--model"),
    _case("simulate", "--strategy=optimal", named="--strategy"),
    *schedulers("simulate"),
    _case("simulate", "--seed=4294967295", "--runs=2", named="--seed"),
    _case("simulate", "--until-failure", "--until-sensing-failure", named="--until-sensing-failure"),
    *out_dirs("simulate"), *unknown("simulate"), no_spin("simulate", "--engine=spin"), *faults("simulate"),
    *vehicle_speeds("simulate"), *choices("simulate", "--semantics"),
    _case("simulate", "--semantics=commit", named="--semantics"),  # the paper model plans whole plans
    # audit
    *numbers("audit", "--km", "--min-spawn-gap-m", "--range-sd-m", "--miss-rate"),
    *numbers("audit", "--stop-rate-per-h"),  # at most one stop starting per vehicle and control step
    *(_case("audit", f"--cells={value}", named="--cells") for value in (*NOT_NUMBERS, "", ",", "21,21", "13")),
    *whole("audit", "--runs", RUNS), *whole("audit", "--seed", SEED),
    *whole("audit", "--snapshots", PER_RUN), *whole("audit", "--opportunity-checks", PER_RUN),
    *whole("audit", "--workers", WORKERS),
    *choices("audit", "--traffic", lists=True), *choices("audit", "--sensing", lists=True),
    *choices("audit", "--model", lists=True), _case("audit", "--model=paper,paper", named="--model"),
    *(_case("audit", f"--bounds-scale={value}", named="--bounds-scale")
      for value in (*NOT_NUMBERS, "", ",", "1,1", "101")),
    *choices("audit", "--engine"), *choices("audit", "--engines", lists=True), *choices("audit", "--executor"),
    _case("audit", "--miss-rate=1.5", named="--miss-rate"),
    *schedulers("audit"), *out_dirs("audit"), *unknown("audit"),
    no_spin("audit", "--engine=spin"), no_spin("audit", "--engines=spin"), *faults("audit"),
    *vehicle_speeds("audit"), *choices("audit", "--semantics", lists=True),
    _case("audit", "--semantics=commit", "--model=paper", named="--semantics"),
    _case("audit", "--semantics=commit,commit", "--model=sound", named="--semantics"),
    # crossval
    *numbers("crossval", "--timeout", "--cell-m"),
    *whole("crossval", "--workers", WORKERS), *whole("crossval", "--seed", SEED),
    *whole("crossval", "--max-reproducers", REPRODUCERS), *whole("crossval", "--horizon", HORIZON),
    *whole("crossval", "--count", CHECK_COUNT),
    *choices("crossval", "--source"), *choices("crossval", "--properties", lists=True),
    *choices("crossval", "--engines", lists=True), *choices("crossval", "--executor"),
    *choices("crossval", "--coverage-target"),
    *(_case("crossval", f"--space={value}", named="--space")
      for value in ("", "left=2", "left=9@0..50,right=0@0..0", "left=1@9..99,right=0@0..0",
                    "left=1@20..10,right=0@0..0", "left=5@0..50,right=5@0..50")),
    *schedulers("crossval"), *out_dirs("crossval"), *unknown("crossval"),
    no_spin("crossval", "--engines=interpreter,spin"),
    *choices("crossval", "--model"), *sound_options("crossval", "--model=sound", commitment=False),
    _case("crossval", "--bounds=paper", named="--bounds"),  # the bounds choose the sound model: --model sound
    _case("crossval", "--model=sound", "--coverage-target=grid", named="--coverage-target"),
    *choices("crossval", "--semantics"),
    _case("crossval", "--semantics=commit", named="--semantics"),  # the sound model's semantics: --model sound
    # the older conformance campaign
    *numbers("conform", "--timeout", "--cell-m"),
    *whole("conform", "--count", COUNT), *whole("conform", "--seed", SEED),
    *whole("conform", "--horizon", HORIZON),
    *choices("conform", "--strategy"), *choices("conform", "--engines", lists=True),
    _case("conform", "--engines=interpreter", named="--engines"),
    *out_dirs("conform"), _case("conform", "--bogus", named="--bogus"),
    no_spin("conform", "--engines=interpreter,spin", "--strategy=sensible"),
    # report: folders that are not there or hold nothing readable (a device, a pipe, malformed JSON), outputs
    *(Case(("report", folder), named) for folder, named in (
        ("missing", "FOLDER='missing': no such folder"), ("a_file", "FOLDER='a_file': not a folder"),
        ("a_folder", "no campaign output"), ("report_zero", "no campaign output"),
        ("report_fifo", "no campaign output"), ("report_malformed", "no campaign output"))),
    *out_files("report"), *out_files("report", "--markdown"), *unknown("report"),
    *whole("report", "--frames", FRAMED),
    *(_case("report", f"--title={value}", named="--title") for value in ("", " ", "a\nb", "x" * 201)),
]


def _ids(cases: Iterable[Case]) -> list[str]:
    return [case.id for case in cases]


# -- the fork server: every case in its own process, without paying the imports each time ---------------------------
# A case is a process of its own as a user starts one (its own folder, argv, stdin, stdout, stderr and process group;
# `python -m` semantics through runpy), forked from a server that has imported every command's modules once: a few
# hundred cases take seconds instead of minutes.
class Done(NamedTuple):
    code: int
    stdout: str
    stderr: str
    seconds: float


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT), "COLUMNS": "200"}


def _vm_peak() -> int:
    return int(Path("/proc/self/status").read_text().split("VmPeak:")[1].split()[0]) * 1024


def _import_every_command() -> None:
    """What a command may load before it reads its input: the CLI, the campaigns, the simulator, every engine
    (explain and shrink load Z3 first), dask's address parser."""
    import distributed.comm.addressing
    import z3

    import ci.audit.campaign
    import ci.cli.main
    import ci.conformance.conform
    import ci.conformance.crossval
    import ci.shared.progress
    import ci.simulation.campaign
    import oracle.explain
    import promela.render
    import sim.parts

    del ci, distributed, oracle, promela, sim, z3


def _serve() -> None:
    """Read one case a line (JSON) from stdin; answer each with how its forked process ended."""
    _import_every_command()
    ceiling = _vm_peak() + HEADROOM
    print(json.dumps({"ceiling": ceiling}), flush=True)
    for line in sys.stdin:
        print(json.dumps(_forked(json.loads(line), ceiling)), flush=True)


def _forked(request: dict[str, Any], ceiling: int) -> dict[str, Any]:
    capture = Path(request["capture"])
    sys.stdout.flush()
    sys.stderr.flush()
    started = time.monotonic()
    pid = os.fork()
    if pid == 0:  # the case
        code = 1
        try:
            os.setpgid(0, 0)
            os.chdir(request["cwd"])
            os.environ.update(request["env"])
            for fd, path, flags in ((0, os.devnull, os.O_RDONLY), (1, capture / "stdout", os.O_WRONLY | os.O_CREAT),
                                    (2, capture / "stderr", os.O_WRONLY | os.O_CREAT)):
                os.dup2(os.open(path, flags), fd)
            if request["ceiling"]:
                resource.setrlimit(resource.RLIMIT_AS, (ceiling, ceiling))
            code = _run_module(request["module"], request["args"])
        finally:
            os._exit(code)
    status = None
    while status is None and time.monotonic() < started + QUICK_S:
        done, found = os.waitpid(pid, os.WNOHANG)
        status = found if done else None
        time.sleep(0.002 if status is None else 0)
    seconds = time.monotonic() - started
    with contextlib.suppress(ProcessLookupError):
        os.killpg(pid, signal.SIGKILL)  # a hung case, and whatever a case started
    if status is None:
        status = os.waitpid(pid, 0)[1]
    return {"code": os.waitstatus_to_exitcode(status), "stdout": (capture / "stdout").read_text(),
            "stderr": (capture / "stderr").read_text(), "seconds": seconds}


def _run_module(module: str, args: list[str]) -> int:
    """``python -m module args`` as the interpreter runs it: its exit code, and a traceback for what escapes."""
    sys.argv = [module, *args]
    warnings.filterwarnings("ignore", "'.*' found in sys.modules", RuntimeWarning)  # imported by the server, on purpose
    try:
        runpy.run_module(module, run_name="__main__", alter_sys=True)
        code = 0
    except SystemExit as done:
        if done.code is None or isinstance(done.code, int):
            code = done.code or 0
        else:
            print(done.code, file=sys.stderr)
            code = 1
    except BaseException:
        traceback.print_exc()
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    return code


@pytest.fixture(scope="module")
def run_case() -> Iterator[Callable[[Case, Path], Done]]:
    """Run a case in ``folder/work`` (its stdout and stderr kept in ``folder/capture``)."""
    server = subprocess.Popen([sys.executable, "-c", "from tests.ci.cli.test_bad_input import _serve; _serve()"],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, cwd=ROOT, env=_env())
    assert server.stdin is not None and server.stdout is not None
    assert server.stdout.readline(), "the fork server did not start"

    def run(case: Case, folder: Path) -> Done:
        assert server.stdin is not None and server.stdout is not None
        capture = folder / "capture"
        capture.mkdir()
        request = {"module": case.module, "args": list(case.args), "cwd": str(folder / "work"),
                   "capture": str(capture), "ceiling": case.ceiling, "env": dict(case.env)}
        server.stdin.write(json.dumps(request) + "\n")
        server.stdin.flush()
        reply = server.stdout.readline()
        assert reply, "the fork server died"
        return Done(**json.loads(reply))

    yield run
    server.stdin.close()
    server.wait(timeout=60)


def _hostile_folder(tmp_path: Path) -> Path:
    work = tmp_path / "work"
    work.mkdir()
    _hostile_files(work)
    return work


def _check(case: Case, done: Done) -> None:
    lines = done.stderr.strip().splitlines()
    assert "Traceback" not in done.stderr, done.stderr
    assert done.code == case.code and len(lines) == 1, (done.code, done.stderr)
    assert case.named in lines[0] and len(lines[0]) < 400, lines[0][:1000]
    assert done.stdout == "", done.stdout
    assert done.seconds < QUICK_S


@pytest.mark.parametrize("case", CASES, ids=_ids(CASES))
def test_bad_input_is_one_line_naming_it_and_its_exit_code(case: Case, tmp_path: Path,
                                                            run_case: Callable[[Case, Path], Done]) -> None:
    _hostile_folder(tmp_path)
    _check(case, run_case(case, tmp_path))


def _limit(address_space: int) -> Callable[[], None]:
    def apply() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (address_space, address_space))

    return apply


FRESH = [c for c in CASES if c.args[:2] in {("plan", "/dev/zero"), ("explain", "urandom.toml"), ("shrink", "fifo.json"),
                                            ("promela", "zero.json"), ("validate", "/dev/urandom")}
         or (c.args[-1] in {"--km=nan", "--horizon=many"} and c.args[0] in {"simulate", "--count"})]


@pytest.fixture(scope="module")
def imports_vm_peak() -> int:
    """What a fresh process takes once every command is imported (bytes of address space), measured once."""
    baseline = subprocess.run([sys.executable, "-c", "from tests.ci.cli.test_bad_input import _import_every_command, "
                               "_vm_peak\n_import_every_command()\nprint(_vm_peak())"],
                              capture_output=True, text=True, timeout=60, env=_env(), cwd=ROOT, check=True)
    return int(baseline.stdout)


@pytest.mark.parametrize("case", FRESH, ids=_ids(FRESH))
def test_bad_input_in_a_fresh_process_under_a_memory_ceiling(case: Case, tmp_path: Path, imports_vm_peak: int) -> None:
    """A sample of the cases as a user starts them (their imports their own), under a ceiling of what the imports
    take and a few hundred MiB more."""
    work = _hostile_folder(tmp_path)
    started = time.monotonic()
    done = subprocess.run([sys.executable, "-m", case.module, *case.args], capture_output=True, text=True,
                          timeout=QUICK_S, cwd=work, env={**_env(), **dict(case.env)},
                          preexec_fn=_limit(imports_vm_peak + HEADROOM))
    _check(case, Done(done.returncode, done.stdout, done.stderr, time.monotonic() - started))


def test_the_memory_ceiling_stops_a_read_without_bound() -> None:
    """What the ceiling is for: a device read whole fails at once instead of eating the machine."""
    done = subprocess.run([sys.executable, "-c", "open('/dev/zero', 'rb').read()"], capture_output=True, text=True,
                          timeout=QUICK_S, preexec_fn=_limit(512 * 2**20))
    assert done.returncode != 0 and "MemoryError" in done.stderr


def test_every_workers_option_has_the_one_bound() -> None:
    """--workers is bounded in one place (``ci.shared.options.WORKERS``), shared by every command that takes it."""
    found = {name: param.type for name, command in cli.commands.items() for param in command.params
             if param.name == "workers"}
    assert set(found) == {"simulate", "audit", "crossval"} and all(kind is WORKERS for kind in found.values())
    assert WORKERS.min == 1 and WORKERS.max == 256


def test_the_cases_cover_every_command_and_every_option_that_takes_a_value() -> None:
    bad = {(case.args[0], case.args[-1].split("=")[0]) for case in CASES if case.module == "ci.cli.main"}
    wanted = {(name, param.opts[0]) for name, command in cli.commands.items() for param in command.params
              if isinstance(param, click.Option) and not param.is_flag}
    assert {name for name, _ in bad} == set(cli.commands)
    assert wanted <= bad, wanted - bad


def test_every_number_option_is_finite_and_every_whole_number_bounded() -> None:
    for name, command in cli.commands.items():
        for param in command.params:
            kind = param.type
            assert not isinstance(kind, click.types.FloatParamType), f"{name} {param.opts[0]}: use a Number"
            if isinstance(kind, click.types.IntParamType):
                assert isinstance(kind, click.IntRange) and kind.min is not None and kind.max is not None, \
                    f"{name} {param.opts[0]}: state its bounds"


@pytest.mark.parametrize("command", ["shrink", "simulate", "audit", "crossval", "conform"])
def test_a_base_invocation_is_good_input(command: str, tmp_path: Path) -> None:
    """What the cases above add their bad value to is accepted: each case fails on its own value alone."""
    module = "ci.conformance.conform" if command == "conform" else "ci.cli.main"
    done = subprocess.run([sys.executable, "-m", module, *BASE[command]], capture_output=True, text=True,
                          timeout=120, cwd=tmp_path, env=_env())
    assert done.returncode in (ExitCode.OK, ExitCode.NO), done.stderr


def test_the_readme_documents_every_exit_code_and_no_other() -> None:
    table = (ROOT / "README.md").read_text().split("| exit code | meaning |")[1].split("\n\n")[0]
    assert {int(code) for code in re.findall(r"^\| (\d+) \|", table, re.MULTILINE)} == {int(c) for c in ExitCode}


@pytest.mark.parametrize("space", [SPACE, DEFAULT_SPACE, "left=2@9..14,right=1@12..18,lanes=right",
                                   "left=3@0..20,right=0@0..0"])
def test_a_space_is_measured_from_its_bounds_as_its_candidates_are_counted(space: str) -> None:
    """--space is refused above a million candidates by arithmetic on its bounds: the count its enumeration gives."""
    from ci.conformance.crossval import parse_space

    parsed = parse_space(space, PAPER_GRID)
    assert parsed.candidates() == sum(1 for _ in parsed._raw())
