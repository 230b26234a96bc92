"""Mutation check: does what CI runs catch each single-rule fault of ``ci.mutation.mutants``?

Usage: python -m ci.mutation.check [--mutants a,b | --rotate K [--date YYYY-MM-DD]] [--count N]
                                   [--crossval-only] [--shared-cache] [--out DIR] [--list]

Each mutant is applied to a scratch copy of the checkout (the files git tracks) and the
detectors ``.ci/run`` runs are tried on it, cheapest first, until one fails: the test files that
mirror the mutated module (``tests/<layer>/test_<module>*.py``, and those it names), the tests of the mutated layer,
``crossval`` on the library, ``crossval`` on CI's exhaustive space, CI's hypothesis campaign on
the 10.5 m grid (with its coverage target; the day's seed, as CI picks it), the same exhaustive
space and 10.5 m hypothesis campaign under the sound model (``--model sound``), then the whole
test suite (``--crossval-only``: the campaigns alone); the tests on every core. The report says
which detector caught each mutant, after how many seconds,
and how small its reproducer is (vehicles and horizon of the shrunk scenario, or the first
failing test). ``--rotate K`` checks K mutants chosen by the date (every mutant at least once
in ``ceil(n / K)`` days: CI's daily share); ``--count N`` the first N of those chosen (a quick
look). A detector that ends without a verdict (a collection error, bad input, a crash) catches nothing: the next one
is tried, and a mutant nothing catches after such an ending has no verdict. Exit 0 when every mutant checked was
caught, 6 when one survived, 3 when none survived but one has no verdict, 2 on bad input.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

from ci.mutation.mutants import MUTANTS, Mutant, mutant
from promela.runner import cache_dir
from spec.errors import ExitCode, OptionError, SuiteError

ROOT = Path(__file__).resolve().parents[2]
CI_SPACE = "left=2@9..14,right=1@12..18,lanes=both"  # CI's exhaustive sweep (.ci/run), every property
#: CI's 10.5 m hypothesis campaign's properties (.ci/run): every one but optimality
CI_FINE_PROPERTIES = "existence,validity,sensible_identity,shortest_length,trace_equality,no_plan_proof"
CI_SOUND_PROPERTIES = f"{CI_FINE_PROPERTIES},motion_safety"
DETECTOR_TIMEOUT_S = 1800.0


@dataclass(frozen=True, slots=True)
class Detector:
    """A check CI runs: the command (in the scratch copy), and how to tell that it caught the fault."""

    name: str
    command: Callable[[Mutant, Path], list[str]]
    caught_codes: tuple[int, ...]  # exit codes that mean "found a fault"; 0 means it did not
    env: tuple[tuple[str, str], ...] = ()  # set for this detector only (as .ci/run sets them)
    tests: bool = False  # pytest on every core with -x: a failure stops the session as an interruption

    def caught(self, done: subprocess.CompletedProcess[str]) -> bool:
        """Whether the run found the fault: one of its exit codes, or (tests) pytest-xdist stopping the session at the
        first failure or error, which it reports as an interruption (exit 2) after the summary line naming it (as
        pytest on one core exits 1 for them); a collection error stops it otherwise and is no catch."""
        if done.returncode in self.caught_codes:
            return True
        return (self.tests and done.returncode == PYTEST_INTERRUPTED and _STOPPED_AT_FAILURE in done.stdout
                and any(_a_test(line) for line in done.stdout.splitlines()))


_STOPPED_AT_FAILURE = "stopping after 1 failures"  # pytest-xdist's words when -x stops the session
PYTEST_INTERRUPTED = 2  # pytest.ExitCode.INTERRUPTED


def _a_test(line: str) -> bool:
    """A summary line naming a test that failed or errored (``ERROR path`` alone is a module that did not import)."""
    kind, _, rest = line.partition(" ")
    return kind == "FAILED" or (kind == "ERROR" and "::" in rest.split(" ", 1)[0])


def _pytest(*targets: str) -> list[str]:
    """The tests as ``ci/test.sh`` runs them (every core, a module's shared fixture on one worker), stopping at the
    first failure."""
    return [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", "-n", "auto", "--dist", "loadgroup",
            *targets]


def _crossval(work: Path, *args: str) -> list[str]:
    return [sys.executable, "-m", "ci.cli.main", "crossval", "--out", str(work), "--max-reproducers", "1", "--json",
            *args]


def _ci_seed() -> str:
    """The day's conformance seed, as ``.ci/run`` picks it (``SEED``, else today's date, UTC)."""
    return os.environ.get("SEED") or datetime.datetime.now(datetime.UTC).strftime("%Y%m%d")


#: The mutants' own self-check would "catch" every mutant (its text is gone): never a detector.
SELF_CHECK = "--ignore=tests/ci/mutation/test_check.py"

#: A campaign's exits that fail CI's run of it: a property failed, or one could not be decided (it claims nothing).
FAILS_CI = (ExitCode.DISAGREE, ExitCode.INCOMPLETE)
#: The sound model's hypothesis campaigns: a property failed (an undecided verdict there is often the interpreter's
#: known limit on a measured draw, which CI lets pass when it is the only one: ``ci.conformance.inconclusive``).
SOUND_DRAWS_FAIL = (ExitCode.DISAGREE,)


def _module_tests(m: Mutant) -> list[str]:
    """The test files that mirror the mutated module (``tests/<layer>/test_<module>*.py``) and those the mutant names
    as written for it, as the run's targets."""
    path = Path(m.path)
    mirrored = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "tests" / path.parent).glob(f"test_{path.stem}*.py"))
    return mirrored + [t for t in m.tests if t not in mirrored]


DETECTORS: tuple[Detector, ...] = (
    Detector("tests of the mutated module", lambda m, work: _pytest(*targets) if (targets := _module_tests(m)) else [],
             (1,), tests=True),
    Detector("tests of the mutated layer", lambda m, work: _pytest(f"tests/{m.path.split('/')[0]}", SELF_CHECK),
             (1,), tests=True),
    Detector("crossval library", lambda m, work: _crossval(work / "library", "--source", "library"),
             FAILS_CI),
    Detector("crossval exhaustive (CI's space)",
             lambda m, work: _crossval(work / "exhaustive", "--source", "exhaustive", "--space", CI_SPACE),
             FAILS_CI),
    Detector("crossval hypothesis 10.5 m (CI's)",
             lambda m, work: _crossval(work / "hypothesis-10.5m", "--source", "hypothesis", "--seed", _ci_seed(),
                                       "--cell-m", "10.5", "--properties", CI_FINE_PROPERTIES,
                                       "--coverage-target", "grid"),
             (*FAILS_CI, ExitCode.COVERAGE_MISSED), (("HYPOTHESIS_PROFILE", "ci"),)),
    Detector("crossval sound exhaustive (CI's space)",
             lambda m, work: _crossval(work / "sound-exhaustive", "--source", "exhaustive", "--space", CI_SPACE,
                                       "--model", "sound"),
             FAILS_CI),
    Detector("crossval sound hypothesis 10.5 m (CI's)",
             lambda m, work: _crossval(work / "sound-hypothesis-10.5m", "--source", "hypothesis", "--seed",
                                       _ci_seed(), "--cell-m", "10.5", "--model", "sound", "--engines",
                                       "interpreter,spin", "--properties", CI_SOUND_PROPERTIES, "--timeout", "60"),
             SOUND_DRAWS_FAIL, (("HYPOTHESIS_PROFILE", "ci"),)),
    Detector("crossval sound commitments exhaustive (CI's space)",
             lambda m, work: _crossval(work / "sound-commit-exhaustive", "--source", "exhaustive", "--space", CI_SPACE,
                                       "--model", "sound", "--semantics", "commit"),
             FAILS_CI),
    Detector("crossval sound commitments hypothesis (CI's)",
             lambda m, work: _crossval(work / "sound-commit-hypothesis", "--source", "hypothesis", "--seed",
                                       _ci_seed(), "--model", "sound", "--semantics", "commit", "--engines",
                                       "interpreter,spin,z3", "--timeout", "60"),
             SOUND_DRAWS_FAIL, (("HYPOTHESIS_PROFILE", "ci"),)),
    Detector("tests (all)", lambda m, work: _pytest("tests", SELF_CHECK), (1,), tests=True),
)
#: The detectors that are cross-validation campaigns (``--crossval-only``: what catches a mutant without the tests).
CROSSVAL = tuple(d for d in DETECTORS if d.name.startswith("crossval"))


@dataclass(slots=True)
class Verdict:
    mutant: str
    caught_by: str | None
    seconds: float
    reproducer: str
    errors: list[str]
    undecided: bool = False  # nothing caught it, and a detector crashed: neither caught nor survived

    def outcome(self) -> str:
        return self.caught_by or ("NO VERDICT (a detector crashed)" if self.undecided else "SURVIVED")


def rotation(count: int, on: datetime.date) -> list[Mutant]:
    """``count`` mutants for the day ``on``: consecutive slices, so that every one comes round in ceil(n/count) days."""
    n = len(MUTANTS)
    start = (on.toordinal() * count) % n
    return [MUTANTS[(start + i) % n] for i in range(min(count, n))]


def scratch_copy(into: Path) -> Path:
    """The checkout's tracked files (as they are on disk) copied into ``into``."""
    listed = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout
    for name in filter(None, listed.decode().split("\0")):
        source = ROOT / name
        if source.is_file():
            target = into / name
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target)
    return into


def apply(m: Mutant, tree: Path) -> None:
    path = tree / m.path
    text = path.read_text()
    if text.count(m.old) != 1:
        raise OptionError("--mutants", m.name, f"its text occurs {text.count(m.old)} times in {m.path}, not once")
    path.write_text(text.replace(m.old, m.new))


def check(m: Mutant, cache: Path, on_detector: Callable[[str], None] | None = None,
          detectors: tuple[Detector, ...] = DETECTORS) -> Verdict:
    """Apply ``m`` to a scratch copy and run the detectors until one catches it."""
    started = time.perf_counter()
    errors: list[str] = []
    with tempfile.TemporaryDirectory(prefix=f"mutant-{m.name}-") as scratch:
        tree = scratch_copy(Path(scratch) / "tree")
        apply(m, tree)
        work = Path(scratch) / "work"
        env = {**os.environ, "PYTHONPATH": str(tree), "OVERTAKE_CACHE": str(cache), "HYPOTHESIS_PROFILE": "dev"}
        for detector in detectors:
            command = detector.command(m, work)
            if not command:
                continue  # nothing of it applies to this mutant (no test file mirrors its module)
            if on_detector:
                on_detector(detector.name)
            try:
                done = subprocess.run(command, cwd=tree, env={**env, **dict(detector.env)},
                                      capture_output=True, text=True, timeout=DETECTOR_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                errors.append(f"{detector.name}: no answer within {DETECTOR_TIMEOUT_S:.0f} s")
                continue
            if detector.caught(done):
                return Verdict(m.name, detector.name, time.perf_counter() - started, _reproducer(done), errors)
            if done.returncode != 0:  # no verdict from this one (a collection error, bad input, a crash): go on
                last = (done.stderr.strip() or done.stdout.strip()).splitlines()[-1:] or ["?"]
                errors.append(f"{detector.name}: crashed, exit {done.returncode}: {last[0][:200]}")
    crashed = any(": crashed, exit " in e for e in errors)
    return Verdict(m.name, None, time.perf_counter() - started, "", errors, undecided=crashed)


def _reproducer(done: subprocess.CompletedProcess[str]) -> str:
    """How small the finding is: the shrunk scenario's size (crossval) or the first failing test (pytest)."""
    try:
        data = json.loads(done.stdout)
    except json.JSONDecodeError:
        failed = [line for line in done.stdout.splitlines() if _a_test(line)]
        return failed[0].split(" ", 1)[1][:160] if failed else "(a test failed)"
    reproducers = data.get("reproducers") or []
    if not reproducers:
        return "(no reproducer: only incomplete verdicts)"
    small = min(reproducers, key=lambda r: (r["vehicles"], r["horizon"]))
    return f"{small['property']}: {small['vehicles']} vehicle(s), horizon {small['horizon']}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mutants", default=None, help="comma-separated names (default: all)")
    parser.add_argument("--rotate", type=int, default=None, help="check this many, chosen by the date")
    parser.add_argument("--date", default=None, help="the rotation's date, YYYY-MM-DD (default: today, UTC)")
    parser.add_argument("--count", type=int, default=None, help="at most this many of those chosen (the first)")
    parser.add_argument("--out", default="out/mutation")
    parser.add_argument("--list", action="store_true")
    parser.add_argument("--crossval-only", action="store_true",
                        help="only the cross-validation campaigns as detectors (does crossval alone catch each?)")
    parser.add_argument("--shared-cache", action="store_true",
                        help="Spin verifiers from the suite's cache (promela.runner.cache_dir: what the campaigns "
                             "before it compiled), not a fresh one: a key holds the rendered model, the flags, the "
                             "tools and the runner's own source, so a mutant that changes any of them compiles anew")
    args = parser.parse_args(argv)
    detectors = CROSSVAL if args.crossval_only else DETECTORS
    try:
        chosen = _chosen(args)
    except SuiteError as error:
        print(f"mutation: error: {error}", file=sys.stderr)
        return error.exit_code
    if args.list:
        for m in MUTANTS:
            print(f"{m.name}: {m.what} ({m.path})")
        return ExitCode.OK
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(f"mutation: {len(chosen)} of {len(MUTANTS)} mutants; detectors: {', '.join(d.name for d in detectors)}",
          file=sys.stderr)
    verdicts = []
    with tempfile.TemporaryDirectory(prefix="mutation-cache-") as fresh:
        cache = str(cache_dir()) if args.shared_cache else fresh
        try:
            for n, m in enumerate(chosen, start=1):
                print(f"mutation: [{n}/{len(chosen)}] {m.name}: {m.what}", file=sys.stderr)
                verdict = check(m, Path(cache), lambda name: print(f"  trying {name} ...", file=sys.stderr),
                                detectors)
                verdicts.append(verdict)
                print(f"  -> {verdict.outcome()} after {verdict.seconds:.0f} s {verdict.reproducer}", file=sys.stderr)
                for line in verdict.errors:
                    print(f"     {line}", file=sys.stderr)
        except KeyboardInterrupt:
            print("mutation: interrupted", file=sys.stderr)
            _write(verdicts, out)
            return ExitCode.INTERRUPTED
    _write(verdicts, out)
    survived = [v.mutant for v in verdicts if v.caught_by is None and not v.undecided]
    undecided = [v.mutant for v in verdicts if v.undecided]
    caught = len(verdicts) - len(survived) - len(undecided)
    print(f"mutation: {caught} of {len(verdicts)} caught" + (f"; survived: {', '.join(survived)}" if survived else "")
          + (f"; no verdict (a detector crashed, none caught it): {', '.join(undecided)}" if undecided else ""))
    if survived:
        return ExitCode.DISAGREE
    return ExitCode.INCOMPLETE if undecided else ExitCode.OK


def _chosen(args: argparse.Namespace) -> list[Mutant]:
    if args.mutants and args.rotate is not None:
        raise OptionError("--rotate", args.rotate, "give --mutants or --rotate, not both")
    if args.count is not None and args.count < 1:
        raise OptionError("--count", args.count, "must be at least 1")
    return _selection(args)[:args.count]


def _selection(args: argparse.Namespace) -> list[Mutant]:
    if args.mutants:
        return [mutant(name.strip()) for name in args.mutants.split(",") if name.strip()]
    if args.rotate is not None:
        if args.rotate < 1:
            raise OptionError("--rotate", args.rotate, "must be at least 1")
        try:
            day = datetime.date.fromisoformat(args.date) if args.date else datetime.datetime.now(datetime.UTC).date()
        except ValueError:
            raise OptionError("--date", args.date, "expected YYYY-MM-DD") from None
        days = math.ceil(len(MUTANTS) / args.rotate)
        print(f"mutation: rotation for {day} ({args.rotate} a day: every mutant within {days} days)", file=sys.stderr)
        return rotation(args.rotate, day)
    return list(MUTANTS)


def _write(verdicts: list[Verdict], out: Path) -> None:
    rows = ["| mutant | caught by | seconds | reproducer |", "|---|---|---|---|"]
    rows += [f"| {v.mutant} | {v.caught_by or f'**{v.outcome().lower()}**'} | {v.seconds:.0f} | {v.reproducer} |"
             for v in verdicts]
    (out / "mutation.md").write_text("# Mutation check\n\n" + "\n".join(rows) + "\n")
    (out / "mutation.json").write_text(json.dumps([asdict(v) for v in verdicts], indent=1))


if __name__ == "__main__":
    sys.exit(main())
