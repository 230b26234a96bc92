"""``ci.conformance.inconclusive``: a campaign's undecided verdicts pass only where the limit is one named as open."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from ci.conformance import inconclusive
from ci.conformance.crossval import VERDICTS_FILE
from spec.errors import ExitCode

SCENARIO = {"lane": "left", "left_lane": [12, 39], "right_lane": [39, 48], "targets": 2, "model": "auto",
            "horizon": 15, "cell_m": 21.0}


def _record(verdicts: dict[str, list[str]], statuses: dict[str, str]) -> str:
    return json.dumps({"campaign": {"source": "hypothesis"},
                       "result": {"scenario": SCENARIO, "verdicts": verdicts, "statuses": statuses}}) + "\n"


HELD = _record({"validity": ["held", ""]}, {"z3/shortest": "plan"})
Z3_OPTIMAL = _record({"optimality": ["incomplete", "a limit was hit: z3/optimal"]},
                     {"z3/optimal": "incomplete", "interpreter/shortest": "plan"})
SPIN = _record({"existence": ["incomplete", "a limit was hit: spin/sensible"]}, {"spin/sensible": "incomplete"})
FAILED = _record({"validity": ["failed", "z3/shortest: invalid"]}, {"z3/shortest": "plan"})


def _campaign(tmp_path: Path, *lines: str) -> str:
    (tmp_path / VERDICTS_FILE).write_text("".join(lines) + '{"torn": ')  # a line an interruption cut short
    return str(tmp_path)


@pytest.mark.parametrize(("lines", "code"), [((HELD,), ExitCode.OK), ((HELD, Z3_OPTIMAL), ExitCode.OK),
                                             ((Z3_OPTIMAL, SPIN), ExitCode.INCOMPLETE),
                                             ((Z3_OPTIMAL, FAILED), ExitCode.DISAGREE)])
def test_only_the_open_limit_passes_and_every_undecided_verdict_is_printed(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], lines: tuple[str, ...], code: ExitCode) -> None:
    assert inconclusive.main([_campaign(tmp_path, *lines), "--open", "z3/optimal"]) == code
    out = capsys.readouterr().out
    assert out.count(json.dumps(SCENARIO)) == len(lines) - lines.count(HELD)
    assert f"exit {int(code)}" in out


def test_without_open_limits_an_incomplete_run_stays_incomplete(tmp_path: Path) -> None:
    assert inconclusive.main([_campaign(tmp_path, Z3_OPTIMAL)]) == ExitCode.INCOMPLETE


@pytest.mark.parametrize("args", [["{missing}"], ["{folder}", "--open", "z3"], ["{folder}", "--open", "z3/a/b"]])
def test_bad_input_is_one_line_and_exit_two(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                            args: list[str]) -> None:
    folder = _campaign(tmp_path, HELD)
    argv = [a.format(missing=str(tmp_path / "none"), folder=folder) for a in args]
    assert inconclusive.main(argv) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("inconclusive: ")
