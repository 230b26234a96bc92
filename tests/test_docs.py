"""The README and docs/: every link resolves, the README stays short, and every command the README and docs/ show
runs as printed (or with --km, --runs or --count made smaller, the override named here; docs/' commands in a slow
test that .ci/run runs)."""

from __future__ import annotations

import itertools
import os
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


@pytest.mark.slow  # the README's campaigns (an audit of every cell size, traffic and sensing model): .ci/run runs them
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


# -- the commands docs/ shows ----------------------------------------------------------------------------------------
#: A command docs/ prints, as a user would copy it: ``overtake ...`` or ``python -m ci.MODULE ...`` (``python3`` and a
#: ``/usr/bin/time -v`` prefix alike), in a code block or inline. A synopsis (``[...]``, ``A | B``, ``...``,
#: ``ci.bench.NAME``) is not one, nor is a command's bare name in prose (``overtake plan``).
DOC_COMMAND = re.compile(r"^(?:/usr/bin/time -v )?(overtake [a-z].* .*|python3? -m ci\.[a-z_.]+(?: .*)?)$")
#: What a placeholder in a printed command stands for when the command is checked.
PLACEHOLDERS = {"FILE": str(ROOT / "spec" / "scenarios" / "paper_example.toml"), "N": "2"}


def _docs_commands() -> list[tuple[str, list[str]]]:
    """(page, argv) of every command docs/ prints, placeholders filled (``DIR`` becomes a folder in the test's tmp)."""
    found: dict[str, tuple[str, list[str]]] = {}
    for page in sorted((ROOT / "docs").glob("*.md")):
        text = page.read_text()
        lines = [line for block in re.findall(r"```\w*\n(.*?)```", text, re.DOTALL)
                 for line in block.replace("\\\n", " ").splitlines()]
        lines += re.findall(r"`([^`]+)`", re.sub(r"```.*?```", "", text, flags=re.DOTALL).replace("\n", " "))
        for line in lines:
            command = " ".join(line.split("  #")[0].removeprefix("$ ").split())
            if DOC_COMMAND.match(command) and not re.search(r"[\[\]|]|\.\.\.", command):
                argv = [PLACEHOLDERS.get(word, word) for word in shlex.split(command.removeprefix("/usr/bin/time -v "))]
                found.setdefault(" ".join(argv), (page.name, argv))
    return sorted(found.values())


def test_docs_show_commands() -> None:
    pages = {page for page, _ in _docs_commands()}
    assert pages >= {"audit.md", "benchmarks.md", "closed-loop.md", "crossval.md", "engines.md", "faults.md",
                     "simulator.md", "sound.md", "usage.md"}, pages


def _command_id(value: object) -> str:
    words = [Path(w).name if w.startswith(str(ROOT)) else w for w in value] if isinstance(value, list) else [value]
    return " ".join(map(str, words[:5]))


@pytest.mark.parametrize(("page", "argv"), _docs_commands(), ids=_command_id)
def test_every_docs_command_parses_as_printed(page: str, argv: list[str], tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    """Each command docs/ prints is one its program accepts: an ``overtake`` command parses (every option exists and
    every value passes its checks, as ``overtake`` would run it); a ``python -m ci...`` module exists and its
    ``--help`` names every option the command gives. (The README's commands are run; these are run, made small, by
    ``test_every_docs_command_runs_as_printed``, a slow test .ci/run runs.)"""
    monkeypatch.chdir(tmp_path)
    argv = [str(tmp_path / "out") if word == "DIR" else word for word in argv]
    if argv[0] == "overtake":
        import click

        from ci.cli.main import cli

        with cli.make_context("overtake", argv[1:2]) as group:
            command = cli.get_command(group, argv[1])
            assert command is not None, f"{page}: no command {argv[1]!r}"
            command.make_context(argv[1], argv[2:], parent=group).close()
        assert isinstance(command, click.Command)
        return
    module, words = argv[2], list(itertools.takewhile(lambda word: not word.startswith("-"), argv[3:]))
    done = subprocess.run([sys.executable, "-m", module, *words, "--help"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120)  # a sub-command's words first: its own options are in its help
    assert done.returncode == 0, f"{page}: {module} --help: {done.stderr[-500:]}"
    for option in (word.split("=")[0] for word in argv[3:] if word.startswith("--")):
        assert option in done.stdout, f"{page}: {module} has no option {option}"


#: What a docs/ command is run with where it does not print these options (its defaults are campaigns of minutes to
#: hours: every cell size, traffic and sensing model, every mutant, a profile's examples): each program's own small
#: sizes, added; where it prints one, ``OVERRIDES`` sets it. Sizes only (--km, --runs, counts) and Z3's time limit,
#: which makes an undecided run end sooner and changes nothing else the command does.
ADDED = {"overtake audit": {"--km": "0.3", "--runs": "1"},
         "overtake simulate": {"--km": "0.3", "--runs": "1"},
         "overtake crossval": {"--count": "5"},
         "python -m ci.bench.audit": {"--km": "0.3"},
         "python -m ci.bench.physics": {"--km": "0.05"},  # in one process over the whole grid: 48 short drives
         "python -m ci.bench.envelope": {"--km": "0.3", "--seeds": "1"},  # one drive per traffic model
         "python -m ci.bench.speeds": {"--km": "0.3"},
         "python -m ci.bench.sound": {"--count": "5"},
         "python -m ci.bench.commit": {"--count": "5"},
         "python -m ci.bench.measured": {"--count": "5"},
         "python -m ci.bench.engines_sound": {"--count": "5", "--timeout": "1"},  # Z3's undecided runs end sooner
         "python -m ci.bench.crossval": {"--sweep-count": "20"},
         "python -m ci.bench.loop": {"--km": "0.3", "--compiled": "2", "--commitments": "2"},
         "python -m ci.conformance.tightness": {"--count": "2"},  # every cell size, profile and model: 32 problems
         "python -m ci.mutation.check": {"--count": "1"}}


def _sizes(argv: list[str]) -> list[str]:
    """``argv`` made small: ``OVERRIDES`` where it gives one of those options (a mutation check: one mutant), and
    the program's ``ADDED`` sizes where it gives none."""
    program = f"python -m {argv[2]}" if argv[0].startswith("python") else " ".join(argv[:2])
    added = ADDED.get(program, {})
    sizes = {**OVERRIDES, **added}
    out = [sizes[argv[i - 1]] if i and argv[i - 1] in sizes else word for i, word in enumerate(argv)]
    return out + [word for option, value in added.items() if option not in argv for word in (option, value)]


@pytest.mark.slow  # about 25 worker-minutes in all: run by .ci/run with the test command (``-m "slow or not slow"``)
@pytest.mark.parametrize(("page", "argv"), _docs_commands(), ids=_command_id)
def test_every_docs_command_runs_as_printed(page: str, argv: list[str], tmp_path: Path) -> None:
    """Each command docs/ prints runs as a user would copy it (from a folder with the checkout's ``spec/`` beside
    it, for the scenario files the commands name), made small only as ``_sizes`` says: it exits with a documented
    answer (0; 1 for "no plan" or a drive that failed; 3 for a verdict an engine's limit left open, as a hypothesis
    campaign's random draws may), never bad input, a traceback or a hang; an option the
    program does not know is bad input (exit 2), so a renamed option fails here."""
    (tmp_path / "spec").symlink_to(ROOT / "spec")
    argv = [str(tmp_path / "out") if word == "DIR" else word for word in argv]
    run = _sizes(argv)
    program = [sys.executable, "-m", "ci.cli.main"] if run[0] == "overtake" else [sys.executable, *run[1:3]]
    args = run[1:] if run[0] == "overtake" else run[3:]
    done = subprocess.run([*program, *args], cwd=tmp_path, capture_output=True, text=True, timeout=900,
                          env={**os.environ, "HYPOTHESIS_PROFILE": "dev"})
    assert "Traceback" not in done.stderr, f"{page}: {' '.join(run)}: {done.stderr[-2000:]}"
    assert done.returncode in (0, 1, 3), f"{page}: {' '.join(run)}: exit {done.returncode}: {done.stderr[-1500:]}"
