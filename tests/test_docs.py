"""The README and docs/: every link resolves, the README stays short, and every command the README shows runs as
printed (or with --km, --runs or --count made smaller, the override named here)."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
README_MAX_LINES = 250
#: What a README command may be run with instead of what it prints: smaller campaigns, nothing else.
OVERRIDES = {"--km": "0.3", "--runs": "1", "--count": "5"}


def _slug(heading: str) -> str:
    """GitHub's anchor for a heading."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_link_resolves(page: Path) -> None:
    text = page.read_text()
    for target in LINK.findall(text):
        if re.match(r"^[a-z]+://", target):
            continue
        path, _, anchor = target.partition("#")
        resolved = (page.parent / path).resolve() if path else page
        assert resolved.exists(), f"{page.name}: {target} does not exist"
        if anchor and resolved.suffix == ".md":
            slugs = {_slug(h) for h in re.findall(r"^#+ (.*)$", resolved.read_text(), re.MULTILINE)}
            assert anchor in slugs, f"{page.name}: {target}: no such heading"


def test_the_readme_is_short() -> None:
    assert len((ROOT / "README.md").read_text().splitlines()) <= README_MAX_LINES


def _readme_commands() -> list[list[str]]:
    """The ``overtake`` commands in the README's code blocks (a ``$`` prompt or none; continued lines joined)."""
    blocks = re.findall(r"```(?:bash)?\n(.*?)```", (ROOT / "README.md").read_text(), re.DOTALL)
    commands = []
    for block in blocks:
        for line in block.replace("\\\n", " ").splitlines():
            for part in line.split("  #")[0].removeprefix("$ ").split("&&"):  # `bash ci/setup.sh` is the set-up
                if part.strip().startswith("overtake "):  # itself, and `bash ci/test.sh` the run of these tests
                    commands.append(shlex.split(part))
    return commands


def _overridden(args: list[str]) -> list[str]:
    out = list(args)
    for i, arg in enumerate(out[:-1]):
        if arg in OVERRIDES:
            out[i + 1] = OVERRIDES[arg]
    return out


def test_the_readme_shows_commands() -> None:
    assert {c[1] for c in _readme_commands()} >= {"demo", "plan", "explain", "crossval", "audit", "simulate", "report"}


@pytest.mark.parametrize("args", _readme_commands(), ids=lambda a: " ".join(a[:3]))
def test_every_readme_command_runs_as_printed(args: list[str], tmp_path: Path) -> None:
    if args[1] == "report":  # a report needs campaigns to read: the README's own, made small
        for made in _readme_commands():
            if made[1] in ("crossval", "simulate"):
                assert _run(_overridden(made), tmp_path) in (0, 1)
    code = _run(_overridden(args), tmp_path)
    assert code in (0, 1), (args, code)


def _run(args: list[str], cwd: Path) -> int:
    done = subprocess.run([sys.executable, "-m", "ci.cli.main", *args[1:]], cwd=cwd, capture_output=True, text=True,
                          timeout=1200)
    assert "Traceback" not in done.stderr, done.stderr[-2000:]
    return done.returncode
