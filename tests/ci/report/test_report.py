"""The report command: campaign folders read into one page and its Markdown, what is skipped said, bad input one line
and exit 2; the page checked in headless Chromium (skipped with a reason where Chromium is absent, never in CI)."""

from __future__ import annotations

import json
import os
import re
import shutil
from pathlib import Path

import pytest

from ci.report.browser import chromium, open_page
from ci.report.collect import collect
from ci.report.histograms import breach_histograms, deviation_histograms
from ci.report.render import to_html
from ci.report.road import reproducer_drawing
from sim.driver.monitor import Breach, BreachKind
from sim.summary import RunSummary
from spec.errors import ExitCode
from tests.conftest import run_cli

pytestmark = pytest.mark.xdist_group("report-campaigns")  # on one worker: the campaigns the report reads are run once


@pytest.fixture(scope="module")
def campaigns(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small crossval, simulate and audit campaign, each in its own folder under one."""
    root = tmp_path_factory.mktemp("campaigns")
    runs = [
        ("crossval", "--source", "library", "--engines", "interpreter", "--out", str(root / "crossval")),
        ("simulate", "--km", "0.3", "--runs", "1", "--seed", "1", "--out", str(root / "sim")),
        ("audit", "--cells", "21", "--traffic", "paper", "--sensing", "exact", "--model", "paper,sound", "--km", "0.3",
         "--runs", "1", "--seed", "1", "--engines", "interpreter", "--out", str(root / "audit")),
    ]
    for args in runs:
        done = run_cli(*args, timeout_s=600)
        assert done.returncode == 0, (args, done.stderr[-500:])
    (root / "notes").mkdir()
    (root / "notes" / "readme.txt").write_text("not a campaign")
    return root


def test_every_campaign_kind_is_read_and_the_other_folder_skipped_with_its_reason(campaigns: Path) -> None:
    report = collect([campaigns])
    assert sorted(kind for _, kind in report.found) == ["audit", "crossval", "simulate"]
    assert [s.key for s in report.sections] == ["crossval-1", "simulate-1", "audit-1"]
    assert report.skipped == []  # a folder one level down that holds no campaign is not a campaign: not listed
    alone = collect([campaigns / "notes"])
    assert alone.sections == [] and "no campaign output" in alone.skipped[0][1]
    questions = report.headline.findings
    assert questions[0].startswith("Do the engines agree? Yes: every property held")
    assert "Not answered: no mutation output given" in questions[3]
    assert questions[4].startswith("What does each model's safety cost in progress? paper in paper traffic, exact "
                                   "sensing: ") and "sound (commit) in paper traffic" in questions[4]
    assert [f.name for f in report.headline.figures] == ["headline-tradeoff-1"]
    assert report.headline.figures[0].png().startswith(b"\x89PNG")
    assert "Not answered: no audit output given" in collect([campaigns / "sim"]).headline.findings[4]
    assert all(s.tables for s in report.sections) and all(t.rows for s in report.sections for t in s.tables)


def _histograms(campaigns: Path) -> int:
    """How many histograms the campaigns' simulation section draws (at least its deviations)."""
    found = sum(1 for s in collect([campaigns]).sections for f in s.figures
                if f.name.endswith(("-deviations", "-breaches")))
    assert found >= 1
    return found


def test_a_simulation_shows_its_deviations_per_action_type_as_histograms(campaigns: Path) -> None:
    """The paper model's tolerance check: every action type a line, every check counted, the tolerance marked."""
    section = next(s for s in collect([campaigns / "sim"]).sections if s.key == "simulate-1")
    runs = [RunSummary.from_json(json.loads(line)["run"]) for line in
            (campaigns / "sim" / "runs.jsonl").read_text().splitlines() if line.strip()]
    figure = next(f for f in section.figures if f.name == "simulate-1-deviations")
    checks = sum(sum(r.tolerance.checks.values()) for r in runs)
    assert checks > 0 and figure.png().startswith(b"\x89PNG") and "tolerance 0.25 per action" in figure.caption
    assert sum(sum(bins) for r in runs for bins in r.tolerance.histogram.values()) == checks


def test_breaches_are_drawn_by_bound_and_nothing_is_drawn_without_data() -> None:
    empty = RunSummary(seed=1)
    assert deviation_histograms([empty], "x") is None and breach_histograms([empty], "x") is None
    run = RunSummary(seed=2)
    for kind, by_m in ((BreachKind.APPEARED, 3.0), (BreachKind.APPEARED, 12.5), (BreachKind.TOO_FAST, 0.4)):
        run.containment.add(Breach(1, 0.1, 5.0, "left 1", 7, kind, by_m, "drive"))
    figure = breach_histograms([run], "x")
    assert figure is not None and figure.name == "x-breaches" and "the 3 recorded of 3 counted" in figure.caption
    other = RunSummary(seed=3)
    other.tolerance.histogram["drive"] = [1, 2]  # bins the first run's do not match: not summed into a wrong figure
    run.tolerance.histogram["drive"] = [1, 2, 3]
    assert deviation_histograms([run, other], "x") is None


def test_a_broken_campaign_file_is_skipped_with_its_reason(campaigns: Path, tmp_path: Path) -> None:
    broken = tmp_path / "audit"
    shutil.copytree(campaigns / "audit", broken)
    (broken / "audit.json").write_text("{not json")
    report = collect([broken, campaigns / "sim"])
    assert [kind for _, kind in report.found] == ["simulate"]
    assert report.skipped[0][0] == str(broken) and report.skipped[0][1].startswith("audit.json:")


def test_the_command_writes_the_page_and_markdown_with_links_that_resolve(campaigns: Path, tmp_path: Path) -> None:
    page, markdown = tmp_path / "r.html", tmp_path / "r.md"
    done = run_cli("report", str(campaigns), "--out", str(page), "--markdown", str(markdown), "--frames", "0")
    assert done.returncode == 0, done.stderr
    assert "Do the engines agree?" in done.stdout and str(page) in done.stdout
    html, text = page.read_text(), markdown.read_text()
    assert "<script" not in html and "http://" not in html and "https://" not in html  # nothing to fetch, nothing run
    # the headline's trade-off, the space-time plot, the audit's three, the simulation's histograms (deviations;
    # breaches when there were any)
    assert html.count("data:image/png;base64,") == 5 + _histograms(campaigns)
    for target in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text):
        assert (markdown.parent / target).is_file(), target
    for output in (html, text, done.stdout):
        assert not re.search(r"\bnan\b", output, re.IGNORECASE)


@pytest.mark.slow  # a kilometre's audit, then its closest call replayed in PyBullet: .ci/run runs it
def test_the_closest_call_of_an_audit_is_replayed_and_drawn(tmp_path: Path) -> None:
    """IDM traffic at 21 m: the paper model collides within a kilometre on this seed (tests/sim/test_frames.py)."""
    out = tmp_path / "audit"
    done = run_cli("audit", "--cells", "21", "--traffic", "following", "--sensing", "exact", "--km", "1", "--runs",
                   "1", "--seed", "20261126", "--engines", "interpreter", "--out", str(out), timeout_s=600)
    assert done.returncode == 0, done.stderr
    report = collect([out], frames=1)
    (figure,) = [f for f in report.sections[0].figures if f.path is None]  # made by the report, not read
    assert figure.caption.startswith("contact") and "replayed from the seed;" in figure.caption
    assert figure.png().startswith(b"\x89PNG")


@pytest.mark.parametrize(("args", "option", "code"), [
    (["/no/such/folder"], "FOLDER='/no/such/folder': no such folder", ExitCode.BAD_INPUT),
    (["{campaigns}", "--out", "/no/such/dir/r.html"], "--out='/no/such/dir/r.html'", ExitCode.BAD_INPUT),
    (["{campaigns}/notes"], "no campaign output to report on", ExitCode.BAD_INPUT),
])
def test_bad_input_is_one_line_and_exit_2(campaigns: Path, args: list[str], option: str, code: int) -> None:
    done = run_cli("report", *(a.format(campaigns=campaigns) for a in args))
    assert done.returncode == code
    lines = done.stderr.strip().splitlines()
    assert option in lines[-1] and "Traceback" not in done.stderr


def test_a_reproducer_is_drawn_as_the_road_for_every_run_its_property_reads(tmp_path: Path) -> None:
    import spec

    scenario_file = Path(spec.__file__).parent / "scenarios" / "paper_example.toml"
    drawing = reproducer_drawing(scenario_file, "d", "existence")
    assert drawing is not None
    assert drawing.svg.startswith("<svg") and drawing.svg.count("interpreter/") >= 1
    assert drawing.svg.count('fill="#1a9850"') >= 2  # the AV in every step drawn
    assert reproducer_drawing(tmp_path / "gone.toml", "d", "existence") is None


# -- in a real browser --------------------------------------------------------------------------------------------
def _browser_or_skip() -> None:
    if chromium() is None:
        if os.environ.get("CI"):
            pytest.fail("CI never skips the browser test: chromium is missing (OVERTAKE_BROWSER=1 bash ci/setup.sh)")
        pytest.skip("chromium is not installed (OVERTAKE_BROWSER=1 bash ci/setup.sh installs Debian's)")
    pytest.importorskip("playwright", reason="playwright is not installed (the dev extra has it)")


def test_the_page_passes_in_headless_chromium(campaigns: Path, tmp_path: Path) -> None:
    _browser_or_skip()
    page, shot = tmp_path / "r.html", tmp_path / "r.png"
    page.write_text(to_html(collect([campaigns]), "test"))
    check = open_page(page, shot)
    assert check.problems() == []
    assert check.blocked == [] and len(check.images) == 5 + _histograms(campaigns)
    assert all(w > 0 for _, w in check.images)
    assert {"headline", "inputs", "crossval-1", "simulate-1", "audit-1"} <= {key for key, _, _ in check.sections}
    assert shot.stat().st_size > 10_000


@pytest.mark.parametrize(("broken", "expected"), [
    ('<img src="missing.png" alt="gone">', "image not loaded: gone"),
    ("<script>throw new Error('planted')</script>", "planted"),
    ('<img src="http://example.invalid/x.png" alt="remote">', "request blocked: http://example.invalid/x.png"),
    ("<table><caption>hollow</caption><tbody></tbody></table>", "empty table: hollow"),
])
def test_a_broken_page_fails_the_browser_check(campaigns: Path, tmp_path: Path, broken: str, expected: str) -> None:
    _browser_or_skip()
    page = tmp_path / "r.html"
    page.write_text(to_html(collect([campaigns / "sim"]), "test").replace("</body>", f"{broken}</body>"))
    problems = open_page(page).problems()
    assert any(expected in p for p in problems), problems
