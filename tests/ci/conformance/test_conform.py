"""The conformance campaign: disagreements are recorded and shrunk, and a campaign resumes."""

from __future__ import annotations

import json
from pathlib import Path

from ci.conformance import conform
from spec.errors import ExitCode
from spec.files import load_scenario
from tests.oracle.test_shrink import liar  # noqa: F401  (fixture)


def test_disagreements_are_shrunk_to_reproducers_and_exit_six(tmp_path: Path, liar) -> None:  # noqa: F811
    code = conform.main(["--engines", "interpreter,liar", "--strategy", "shortest", "--count", "30",
                         "--seed", "5", "--out", str(tmp_path)])
    records = [json.loads(line) for line in (tmp_path / "results.jsonl").read_text().splitlines()]
    bad = [r for r in records if r["disagreements"]]
    assert code == ExitCode.DISAGREE and len(records) == 30 and bad
    for record in bad:
        repro = load_scenario(record["reproducer"])
        assert len(repro.left_lane) == 2  # the liar's trigger, and nothing else


def test_campaign_resumes_without_redoing_scenarios(tmp_path: Path) -> None:
    args = ["--engines", "interpreter,interpreter", "--strategy", "sensible", "--seed", "9", "--out", str(tmp_path)]
    assert conform.main([*args, "--count", "10"]) == 0
    with (tmp_path / "results.jsonl").open("a") as log:
        log.write('{"index": 10, "cut sh')  # an interrupted write
    assert conform.main([*args, "--count", "15"]) == 0
    indices = [json.loads(line)["index"] for line in (tmp_path / "results.jsonl").read_text().splitlines()
               if line.endswith("}")]
    assert sorted(indices) == list(range(15))  # each scenario once: the first ten were not decided again


def test_unknown_engine_is_bad_input(tmp_path: Path) -> None:
    assert conform.main(["--engines", "interpreter,nope", "--out", str(tmp_path)]) == 2
