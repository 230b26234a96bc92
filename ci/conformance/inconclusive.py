"""A finished crossval campaign's undecided verdicts, each printed, judged against the limits the docs name as open.

Usage: python -m ci.conformance.inconclusive OUT [--open z3/optimal]

``overtake crossval`` exits 3 when no property failed but an engine hit its limit on some scenario: nothing is
claimed there. CI's daily campaigns draw new scenarios every day, and one engine run is known not to finish within
the limit on some of them (Z3's ``optimal`` under the paper's rules: docs/engines.md, "Z3's optimal under the
paper's rules"). This prints every verdict of ``OUT/verdicts.jsonl`` that did not hold, with its scenario (a line
that reproduces it: ``overtake crossval`` on a scenario file of it, or ``oracle.planner.solve``), and exits

- 0 when every one is "incomplete" and every incomplete run of it is one ``--open`` names (the known limit: CI
  goes on, the lines stay in its log);
- 3 (``ExitCode.INCOMPLETE``) when another run was incomplete (a limit nobody said was open);
- 6 (``ExitCode.DISAGREE``) when a property failed;
- 2 on bad input (no such campaign, a malformed ``--open``).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any, NamedTuple

from ci.conformance.crossval import VERDICTS_FILE
from ci.conformance.properties import Verdict
from ci.shared.records import read_records
from spec.answers import Status
from spec.errors import ExitCode, OptionError, SuiteError


def open_runs(text: str) -> frozenset[str]:
    """``--open``: engine/strategy pairs, comma-separated (``z3/optimal``)."""
    runs = frozenset(part.strip() for part in text.split(",") if part.strip())
    for run in runs:
        engine, _, strategy = run.partition("/")
        if not engine or not strategy or "/" in strategy:
            raise OptionError("--open", text, f"{run!r} is not ENGINE/STRATEGY (as in z3/optimal)")
    return runs


class Undecided(NamedTuple):
    """A verdict that did not hold: the property, its verdict and detail, the scenario, the runs that were
    incomplete."""

    name: str
    verdict: str
    detail: str
    scenario: dict[str, Any]
    runs: list[str]

    def within(self, known: frozenset[str]) -> bool:
        """Whether it is undecided only because runs ``known`` as open hit their limit."""
        return self.verdict == Verdict.INCOMPLETE.value and bool(self.runs) and set(self.runs) <= known


def undecided(records: Iterable[dict[str, Any]]) -> list[Undecided]:
    """Every verdict that did not hold."""
    out = []
    for record in records:
        result = record.get("result", {})
        runs = sorted(run for run, status in result.get("statuses", {}).items() if status == Status.INCOMPLETE.value)
        for name, (verdict, detail) in result.get("verdicts", {}).items():
            if verdict != Verdict.HELD.value:
                out.append(Undecided(name, verdict, detail, result.get("scenario", {}), runs))
    return out


def judge(found: Sequence[Undecided], known: frozenset[str]) -> ExitCode:
    """The exit code (module docstring) for these undecided verdicts."""
    if any(u.verdict != Verdict.INCOMPLETE.value for u in found):
        return ExitCode.DISAGREE
    return ExitCode.OK if all(u.within(known) for u in found) else ExitCode.INCOMPLETE


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("out", help="the campaign's --out folder")
    parser.add_argument("--open", default="", help="engine/strategy runs whose limit the docs name as open")
    args = parser.parse_args(argv)
    try:
        known = open_runs(args.open)
        path = Path(args.out) / VERDICTS_FILE
        if not path.is_file():
            raise OptionError("OUT", args.out, f"no {VERDICTS_FILE} there: not a crossval campaign's folder")
        found = undecided(read_records(path))
    except SuiteError as err:
        print(f"inconclusive: {err}", file=sys.stderr)
        return int(err.exit_code)
    for u in found:
        tag = "open limit" if u.within(known) else u.verdict
        print(f"{tag}: {u.name} ({u.detail}; incomplete: {', '.join(u.runs) or 'none'}) on {json.dumps(u.scenario)}")
    code = judge(found, known)
    print(f"inconclusive: {len(found)} verdict(s) not held in {path}; exit {int(code)} ({code.name.lower()})")
    return int(code)


if __name__ == "__main__":
    raise SystemExit(main())
