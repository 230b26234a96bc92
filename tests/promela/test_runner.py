"""Every ending of pan gets its documented answer at the runner itself (``runner._pan``, ``Server.run``, ``_replay``,
``_compile``, ``search``), not only through the cross-engine pipeline: a plan only from the goal's trail, "no plan
within the horizon" only from a complete search's clean exit, "incomplete" only for a named limit, and an engine
error naming pan's exit code or signal for anything else.

``pan_outputs/`` holds pan's stdout then stderr, recorded with Spin 6.5.2 (6 December 2019) and gcc 12.2.0 from the
cached verifiers (``runner.verifier``: ``-dfs`` sensible, ``-bfs`` shortest with -DBFS), run as ``_pan`` runs them
(``-E -n -m<depth> -w16``, OVERTAKE_SCENARIO set to ``scenario_values``), all exiting 0 unless named below.
plan: one_target, final model. no_plan: the library's no_plan_within_horizon. depth: the same with -m3.
depth_with_trail: three targets and one oncoming (horizon 30) with -m24. memory: -w29, a 4 GB hash table past
-DMEMLIM=2048 (pan's real bound, hit at the table instead of mid-search). interrupted: SIGINT 0.2 s into -w27 (pan
catches it: "Interrupted", "errors: 0", exit 0). malformed_scenario: OVERTAKE_SCENARIO="0 3 12" (the model exits 2).
other_assertion: three left vehicles in the model rendered for two slots, compiled with the runner's CFLAGS (an
array bound, not the goal). no_plan_with_progress: prep_case_a under the final model, breadth first (pan prints
its progress lines before its banner). Signals, other exit codes, no output and unknown lines are synthesised
from these.
"""

from __future__ import annotations

import signal
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from promela import runner
from spec.answers import SearchResult, Status, Strategy
from spec.errors import EngineError
from spec.models import ModelKind
from spec.scenario import make_scenario, problem_for

OUTPUTS = Path(__file__).with_name("pan_outputs")
PROBLEM = problem_for(make_scenario("left", [12], [], 1), ModelKind.FINAL)


def recorded(name: str) -> str:
    return (OUTPUTS / f"{name}.txt").read_text()


def answer(folder: Path, returncode: int, text: str, trail: bool) -> SearchResult:
    """``_pan``'s answer when pan ends with ``returncode`` having printed ``text`` and written a trail or not."""
    if trail:
        (folder / f"{runner.MODEL_FILE}.trail").write_text("-2:-2:-2\n")
    return runner._pan(folder, lambda args, limit: (returncode, text), PROBLEM, 5.0, time.perf_counter())


# -- _pan on recorded and synthesised endings -------------------------------------------------------------------
STORED_WITH_PROGRESS = 6600  # its "states, stored"
RECORDED_ANSWERS = [  # recording, trail written, answer: status, detail, states stored
    ("plan-dfs", True, Status.PLAN, "a trail to replay", 441),
    ("plan-bfs", True, Status.PLAN, "a trail to replay", 53),
    ("no_plan-dfs", False, Status.NO_PLAN_WITHIN_HORIZON, "no plan within 30 actions (search completed)", 30),
    ("no_plan-bfs", False, Status.NO_PLAN_WITHIN_HORIZON, "no plan within 30 actions (search completed)", 30),
    # prep_case_a under the final model alone (breadth first): pan's progress lines come before its banner
    ("no_plan_with_progress-bfs", False, Status.NO_PLAN_WITHIN_HORIZON,
     "no plan within 30 actions (search completed)", STORED_WITH_PROGRESS),
    ("depth-dfs", False, Status.INCOMPLETE, "pan: max search depth too small", 3),
    ("depth-bfs", False, Status.INCOMPLETE, "pan: max search depth too small", 7),
    ("depth_with_trail-dfs", True, Status.INCOMPLETE, "pan: max search depth too small", 893),  # nothing claimed
    ("memory-dfs", False, Status.INCOMPLETE, "pan: memory limit reached", 0),  # "errors: 0" too
    ("memory-bfs", False, Status.INCOMPLETE, "pan: memory limit reached", 0),
]


@pytest.mark.parametrize(("name", "trail", "status", "detail", "stored"), RECORDED_ANSWERS,
                         ids=[row[0] for row in RECORDED_ANSWERS])
def test_each_recorded_ending_gets_its_documented_answer(tmp_path: Path, name: str, trail: bool, status: Status,
                                                         detail: str, stored: int) -> None:
    result = answer(tmp_path, 0, recorded(name), trail)
    assert (result.status, result.detail, result.states_explored) == (status, detail, stored)


def test_a_time_out_is_incomplete_never_no_plan(tmp_path: Path) -> None:
    def hangs(args: list[str], limit: float | None) -> tuple[int, str]:
        raise subprocess.TimeoutExpired(["pan", *args], limit or 0)

    result = runner._pan(tmp_path, hangs, PROBLEM, 0.5, time.perf_counter())
    assert result.status is Status.INCOMPLETE and "time limit 0.5 s" in result.detail


@pytest.mark.parametrize(("returncode", "text", "trail", "said"), [
    (0, recorded("plan-dfs"), False, "exit 0): pan:1: assertion violated  !(reached)"),  # the goal, but no trail
    (0, recorded("other_assertion-dfs"), True, "exit 0): pan:1: assertion violated - invalid array index"),
    (0, recorded("interrupted-dfs"), False, "exit 0): Interrupted"),  # "errors: 0", "Search not completed"
    (2, recorded("malformed_scenario-dfs"), False, "exit 2): overtake: malformed OVERTAKE_SCENARIO"),
    (1, recorded("no_plan-dfs"), False, "exit 1): (Spin Version"),  # a complete search, but not a clean exit
    (3, recorded("plan-dfs"), True, "exit 3)"),
    (0, "", False, "exit 0): no output"),
    (0, "pan: a line the runner does not know\n", False, "exit 0): pan: a line the runner does not know"),
    (0, recorded("plan-dfs").split("\n\n")[0], True, "exit 0): pan:1:"),  # cut before its summary
    (0, recorded("no_plan-dfs").replace("errors: 0", "errors: ?"), False, "exit 0)"),
    (0, "pan: a line the runner does not know\n" + recorded("no_plan-dfs"), False,
     "exit 0): pan: a line the runner does not know"),
    (0, recorded("no_plan-dfs").replace("hash conflicts:", "pan: hash table full\nhash conflicts:"), False,
     "exit 0): (Spin Version"),
    (0, recorded("no_plan-dfs") + "pan: something after the report\n", False, "exit 0): (Spin Version"),
    (0, recorded("no_plan-dfs").replace("Full statespace search for:", "Partial search for:"), False,
     "exit 0): (Spin Version"),
], ids=["goal-without-trail", "other-assertion", "interrupted", "malformed-scenario", "exit-1-after-errors-0",
        "exit-3-after-a-trail", "no-output", "unknown-line", "no-summary", "unreadable-summary",
        "unknown-line-before-a-clean-report", "unknown-line-inside-it", "unknown-line-after-it", "not-a-full-search"])
def test_an_unknown_ending_is_an_engine_error_with_its_exit_code_never_no_plan(
        tmp_path: Path, returncode: int, text: str, trail: bool, said: str) -> None:
    with pytest.raises(EngineError) as caught:
        answer(tmp_path, returncode, text, trail)
    assert f"pan failed ({said}" in str(caught.value)


@pytest.mark.parametrize("number", [signal.SIGKILL, signal.SIGSEGV, signal.SIGABRT], ids=lambda s: s.name)
@pytest.mark.parametrize(("text", "trail"), [("", False), ("pan:1: assertion violated  !(reached)\n", True),
                                             (recorded("plan-dfs"), True), (recorded("no_plan-dfs"), False)],
                         ids=["no-output", "partial", "after-a-trail", "after-errors-0"])
def test_a_signal_is_an_engine_error_never_an_answer(tmp_path: Path, number: signal.Signals, text: str,
                                                     trail: bool) -> None:
    with pytest.raises(EngineError, match=rf"pan failed \(signal {int(number)} \({number.name}\)\)"):
        answer(tmp_path, -int(number), text, trail)


@pytest.mark.parametrize("name", sorted(p.stem for p in OUTPUTS.glob("*.txt")))
@pytest.mark.parametrize("returncode", [2, -11])
def test_no_recorded_output_is_an_answer_without_a_clean_exit(tmp_path: Path, name: str, returncode: int) -> None:
    with pytest.raises(EngineError, match=r"pan failed \((exit|signal) \d+"):
        answer(tmp_path, returncode, recorded(name), trail=True)


# -- the server's replies, from a stand-in verifier --------------------------------------------------------------
def fake_pan(folder: Path, ending: str, output: str = "") -> Path:
    """A stand-in verifier: plainly run, it prints ``output`` and ends with ``ending`` ("exit N" or "signal N"); with
    --serve it says "ready", then answers each request by writing ``output`` to out.txt and replying ``ending`` (when
    ``ending`` is empty it stops instead)."""
    (folder / "output.txt").write_text(output)
    kind, _, number = ending.partition(" ")
    plain_end = f"kill -{number} $$" if kind == "signal" else f"exit {number or 0}"
    serve = f'cat "{folder}/output.txt" > out.txt; echo "{ending}"' if ending else "exit 0"
    script = folder / "pan"
    script.write_text("\n".join(["#!/bin/sh", 'if [ "$1" = --serve ]; then', "  echo ready",
                                  f"  while read -r request; do {serve}; done", "else", f'  cat "{folder}/output.txt"',
                                  f"  {plain_end}", "fi", ""]))
    script.chmod(0o755)
    return script


@pytest.fixture
def fakes(tmp_path: Path) -> Iterator[Path]:
    """A folder for stand-in verifiers; their servers are stopped afterwards."""
    yield tmp_path
    for key in [k for k in runner._SERVERS if k[0].is_relative_to(tmp_path)]:
        runner._SERVERS.pop(key).close()


def served_answer(fakes: Path, reply: str, output: str = "") -> SearchResult:
    """``_pan``'s answer through a server whose every run prints ``output`` and is answered with ``reply``."""
    server = runner.Server(fake_pan(fakes, reply, output))
    try:
        return runner._pan(server.folder, lambda args, limit: server.run("0 1 12 0 1 0 30", args, limit),
                           PROBLEM, 5.0, time.perf_counter())
    finally:
        server.close()


def test_a_served_clean_exit_reads_the_runs_output(fakes: Path) -> None:
    result = served_answer(fakes, "exit 0", recorded("no_plan-dfs"))
    assert result.status is Status.NO_PLAN_WITHIN_HORIZON and result.states_explored == 30


def test_a_served_signal_is_an_engine_error_naming_it(fakes: Path) -> None:
    with pytest.raises(EngineError, match=r"pan failed \(signal 11 \(SIGSEGV\)\): \(Spin Version"):
        served_answer(fakes, "signal 11", recorded("no_plan-dfs"))


def test_a_served_timeout_is_incomplete(fakes: Path) -> None:
    result = served_answer(fakes, "timeout", recorded("no_plan-dfs"))
    assert result.status is Status.INCOMPLETE and "time limit" in result.detail


@pytest.mark.parametrize("reply", ["error fork failed", "error waitpid failed", "signal 0", "exit", "exit -1",
                                   "exit 0 0", "bogus 3", "ready"])
def test_a_server_reply_it_does_not_know_is_an_engine_error(fakes: Path, reply: str) -> None:
    with pytest.raises(EngineError, match=f"the verifier's server answered '{reply}'"):
        served_answer(fakes, reply, recorded("no_plan-dfs"))


def test_a_server_that_stops_is_an_engine_error(fakes: Path) -> None:
    with pytest.raises(EngineError, match="the verifier's server has stopped"):
        served_answer(fakes, "", recorded("no_plan-dfs"))


def test_a_served_run_without_an_output_file_is_no_output(fakes: Path) -> None:
    fake = fakes / "pan"  # replies as a run that could not open out.txt (serve.c's exit 121), writing none
    fake.write_text('#!/bin/sh\necho ready\nwhile read -r request; do echo "exit 121"; done\n')
    fake.chmod(0o755)
    server = runner.Server(fake)
    try:
        assert server.run("", ["-E"], 5.0) == (121, "") and not (server.folder / "out.txt").exists()
    finally:
        server.close()


# -- through search, served and not: an unknown ending is never an answer ---------------------------------------
@pytest.mark.requires_spin
@pytest.mark.parametrize("serve", [True, False], ids=["served", "unserved"])
@pytest.mark.parametrize(("ending", "output", "said"), [
    ("exit 0", "pan: a line the runner does not know\n", r"pan failed \(exit 0\): pan: a line the runner"),
    ("signal 11", recorded("no_plan-dfs"), r"pan failed \(signal 11 \(SIGSEGV\)\)"),
    ("exit 0", recorded("interrupted-dfs"), r"pan failed \(exit 0\): Interrupted"),
], ids=["unknown-line", "signal-after-errors-0", "interrupted"])
def test_search_reports_an_unknown_ending_as_an_engine_error_never_no_plan(
        fakes: Path, monkeypatch: pytest.MonkeyPatch, serve: bool, ending: str, output: str, said: str) -> None:
    fake = fake_pan(fakes, ending, output)
    monkeypatch.setattr(runner, "verifier", lambda shape, strategy: runner.Verifier(fake, False))
    with pytest.raises(EngineError, match=said):
        runner.search(PROBLEM, Strategy.SENSIBLE, serve=serve)


@pytest.mark.requires_spin
@pytest.mark.parametrize("serve", [True, False], ids=["served", "unserved"])
def test_search_through_a_stand_in_reads_a_clean_no_plan(fakes: Path, monkeypatch: pytest.MonkeyPatch,
                                                         serve: bool) -> None:
    fake = fake_pan(fakes, "exit 0", recorded("no_plan-bfs"))
    monkeypatch.setattr(runner, "verifier", lambda shape, strategy: runner.Verifier(fake, False))
    assert runner.search(PROBLEM, Strategy.SHORTEST, serve=serve).status is Status.NO_PLAN_WITHIN_HORIZON


@pytest.mark.requires_spin
def test_the_time_limit_counts_the_search_not_the_verifiers_build(fakes: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Unserved: the stand-in's run is timed here (a served run's limit is kept by the real server, from the same
    start)."""
    fake = fake_pan(fakes, "exit 0", recorded("no_plan-bfs"))
    fake.write_text(fake.read_text().replace("#!/bin/sh\n", "#!/bin/sh\nsleep 0.2\n"))

    def slow_build(shape: object, strategy: Strategy) -> runner.Verifier:
        time.sleep(2.5)  # a compile on a busy machine, longer than the limit
        return runner.Verifier(fake, False)

    monkeypatch.setattr(runner, "verifier", slow_build)
    done = runner.search(PROBLEM, Strategy.SHORTEST, timeout_s=2.0, serve=False)  # the search: about 0.2 s
    assert done.status is Status.NO_PLAN_WITHIN_HORIZON, done.detail


# -- the replay and the compile: their failures are engine errors -------------------------------------------------
@pytest.mark.parametrize(("ending", "said"), [
    ((-9, "INIT 0 0 0 | 12 |\n"), r"replay of pan's trail failed \(signal 9 \(SIGKILL\)\): INIT"),
    ((1, "error: there are 0 trail files:\n"), r"replay of pan's trail failed \(exit 1\): error: there are 0"),
    ((0, "no states\n"), "printed no states"),
    (None, "took over 60 s"),
], ids=["signal", "exit-1", "no-states", "time-out"])
def test_a_replay_that_does_not_end_cleanly_is_an_engine_error_never_a_plan(
        ending: tuple[int, str] | None, said: str) -> None:
    def execute(args: list[str], limit: float | None) -> tuple[int, str]:
        if ending is None:
            raise subprocess.TimeoutExpired(args, limit or 0)
        return ending

    with pytest.raises(EngineError, match=said):
        runner._replay(execute, ["-r"], PROBLEM, 0)


def compiling(monkeypatch: pytest.MonkeyPatch, spin: subprocess.CompletedProcess[str], writes_pan_c: bool,
              gcc: subprocess.CompletedProcess[str]) -> None:
    """``_run`` standing in for spin and gcc."""
    def run(args: list[str], cwd: Path | None = None, env: dict[str, str] | None = None,
            timeout: float | None = None) -> subprocess.CompletedProcess[str]:
        if args[0] == "spin" and writes_pan_c and cwd is not None:
            (cwd / "pan.c").write_text("int main(void) { return 0; }\n")
        return spin if args[0] == "spin" else gcc

    monkeypatch.setattr(runner, "_run", run)


def done(code: int, stdout: str = "", stderr: str = "") -> subprocess.CompletedProcess[str]:
    return subprocess.CompletedProcess([], code, stdout, stderr)


@pytest.mark.parametrize(("spin", "writes_pan_c", "gcc", "said"), [
    (done(3, stderr="spin: model.pml:3, Error: syntax error\n"), False, done(0),
     "spin -a failed on the rendered model: spin: model.pml:3, Error: syntax error"),
    (done(0, stdout="nothing to do\n"), False, done(0), "spin -a failed on the rendered model: nothing to do"),
    (done(0), True, done(1, stderr="pan.c:1: warning: x\npan.c:12:5: error: expected ';'\n"),
     "gcc failed on pan.c: pan.c:12:5: error: expected ';'"),
    (done(0), True, done(-9), "gcc failed on pan.c: no output, signal 9 (SIGKILL)"),
], ids=["spin-fails", "spin-writes-no-pan-c", "gcc-fails", "gcc-killed"])
def test_a_compile_failure_is_an_engine_error_with_the_tools_last_line(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, spin: subprocess.CompletedProcess[str], writes_pan_c: bool,
        gcc: subprocess.CompletedProcess[str], said: str) -> None:
    compiling(monkeypatch, spin, writes_pan_c, gcc)
    with pytest.raises(EngineError) as caught:
        runner._compile(tmp_path, "active proctype p() { skip }\n", runner._flags(Strategy.SENSIBLE))
    assert str(caught.value) == said


def test_a_thread_keeps_at_most_max_servers_the_least_recently_used_stopped_first(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """A campaign over many sets of bounds meets many verifiers: past ``MAX_SERVERS`` the least recently used stops."""
    class Fake:
        def __init__(self, pan: Path) -> None:
            self.pan, self.closed = pan, False

        def alive(self) -> bool:
            return not self.closed

        def close(self) -> None:
            self.closed = True

    monkeypatch.setattr(runner, "Server", Fake)
    monkeypatch.setattr(runner, "_SERVERS", {})
    pans = [tmp_path / f"pan{i}" for i in range(runner.MAX_SERVERS + 2)]
    first = runner._server(pans[0])
    for pan in pans[1:runner.MAX_SERVERS]:
        runner._server(pan)
    assert runner._server(pans[0]) is first  # used again: now the most recent
    runner._server(pans[runner.MAX_SERVERS])  # one too many: pans[1], the least recently used, stops
    kept = {k[0] for k in runner._SERVERS}
    assert len(kept) == runner.MAX_SERVERS and pans[0] in kept and pans[1] not in kept and not first.closed
