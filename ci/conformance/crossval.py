"""Cross-validation campaigns: every registered property, on scenarios from a source, every verdict kept.

Sources: the built-in library; an exhaustive sweep of a bounded space (``Space``: its size is
known before the first scenario runs, and every scenario in it is checked); hypothesis
(``ci.conformance.hypo``: its own generation and shrinking). Each scenario's verdicts (one per property),
run latencies and the rules it exercised (``oracle.coverage``) are appended to
``OUT/verdicts.jsonl`` as soon as they are decided, under the campaign's key, so an interrupted
campaign started again checks only what is missing (a torn last line is skipped). A finding
never stops a campaign: an engine error is a failed ``validity``, a time-out an incomplete
verdict. After the sweep each failed property's first failures are shrunk to reproducers
(``ci.conformance.repro``), and the summary is written as Markdown, JSON and JUnit XML.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import math
import re
from collections import Counter
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

import numpy as np

from ci.conformance.properties import PROPERTIES, PropertyName, Runs, Verdict
from ci.shared.executors import ExecutorChoice, run_jobs
from ci.shared.records import append, campaign_lock, open_for_append, read_records
from oracle.coverage import CoverageTarget, rules_exercised, rules_on
from spec.answers import Limits, Status
from spec.constants import DEFAULT_HORIZON
from spec.errors import OptionError, ScenarioError
from spec.escapes import COMMIT, Semantics
from spec.files import scenario_from_dict, scenario_to_dict
from spec.grid import PAPER_GRID, Grid, grid_for
from spec.lanes import Lane
from spec.library import BUILTINS
from spec.scenario import Scenario, make_scenario
from spec.sound import Sound, sound_to_table

VERDICTS_FILE = "verdicts.jsonl"
BATCH = 8  # scenarios per job: few enough for a smooth progress bar, enough to amortise a job's start
MAX_TARGETS = 3


@dataclass(frozen=True, slots=True)
class Space:
    """A bounded space of scenarios: at most ``left_max`` same-direction vehicles in ``left_cells``, at most
    ``right_max`` oncoming ones in ``right_cells``, the AV in each of ``lanes``, every target count."""

    left_max: int = 2
    left_cells: tuple[int, int] = (8, 20)
    right_max: int = 1
    right_cells: tuple[int, int] = (12, 30)
    lanes: tuple[Lane, ...] = (Lane.LEFT, Lane.RIGHT)

    def describe(self) -> str:
        lanes = "both" if len(self.lanes) == 2 else self.lanes[0].value
        return (f"left={self.left_max}@{self.left_cells[0]}..{self.left_cells[1]},"
                f"right={self.right_max}@{self.right_cells[0]}..{self.right_cells[1]},lanes={lanes}")

    def candidates(self) -> int:
        """How many scenarios the space names before validation (vehicle sets x lanes x target counts), from its
        bounds: as many vehicle sets per lane as ways to choose up to N of its cells."""
        def vehicle_sets(most: int, cells: tuple[int, int]) -> int:
            return sum(math.comb(cells[1] - cells[0] + 1, n) for n in range(most + 1))

        return (len(self.lanes) * (MAX_TARGETS + 1) * vehicle_sets(self.left_max, self.left_cells)
                * vehicle_sets(self.right_max, self.right_cells))

    def _raw(self) -> Iterator[tuple[Lane, tuple[int, ...], tuple[int, ...], int]]:
        left_range = range(self.left_cells[0], self.left_cells[1] + 1)
        right_range = range(self.right_cells[0], self.right_cells[1] + 1)
        lefts = [c for n in range(self.left_max + 1) for c in itertools.combinations(left_range, n)]
        rights = [c for n in range(self.right_max + 1) for c in itertools.combinations(right_range, n)]
        for lane in self.lanes:
            for targets in range(MAX_TARGETS + 1):  # one vehicle moved at a time: a warm start's guess often holds
                for left in lefts:
                    yield from ((lane, left, right, targets) for right in rights)

    def scenarios(self, grid: Grid, horizon: int | None) -> Iterator[Scenario]:
        """Every valid scenario of the space, in a fixed order (invalid ones: too many targets, an initial
        collision, are left out)."""
        for lane, left, right, targets in self._raw():
            try:
                yield make_scenario(lane, list(left), list(right), targets,
                                    horizon=DEFAULT_HORIZON if horizon is None else horizon, grid=grid)
            except ScenarioError:
                continue


MAX_CANDIDATES = 1_000_000  # every candidate is built and checked by every engine: a million is days of runs
_SPACE = re.compile(r"^left=(\d+)@(\d+)\.\.(\d+),right=(\d+)@(\d+)\.\.(\d+)(?:,lanes=(left|right|both))?$")


def parse_space(text: str, grid: Grid) -> Space:
    """``left=N@A..B,right=M@C..D[,lanes=left|right|both]``; cells must lie in the grid's window."""
    found = _SPACE.match(text.replace(" ", ""))
    if not found:
        raise OptionError("--space", text, "expected left=N@A..B,right=M@C..D[,lanes=left|right|both]")
    ln, la, lb, rn, ra, rb = (int(g) for g in found.groups()[:6])
    lanes = {"left": (Lane.LEFT,), "right": (Lane.RIGHT,)}.get(found.group(7) or "both", (Lane.LEFT, Lane.RIGHT))
    for low, high in ((la, lb), (ra, rb)):
        if not 0 <= low <= high <= grid.road_cells:
            raise OptionError("--space", text, f"cells must satisfy 0 <= A <= B <= {grid.road_cells} on this grid")
    if ln > 5 or rn > 5:
        raise OptionError("--space", text, "at most 5 vehicles per lane (the space grows as cells^vehicles)")
    space = Space(ln, (la, lb), rn, (ra, rb), lanes)
    if space.candidates() > MAX_CANDIDATES:
        raise OptionError("--space", text, f"{space.candidates():,} candidates, more than {MAX_CANDIDATES:,} (each "
                                           f"one is checked)")
    return space


def library_scenarios(grid: Grid) -> list[Scenario]:
    """The built-in scenarios (on the paper's grid; another grid has no library)."""
    if grid != PAPER_GRID:
        paper = f"{float(PAPER_GRID.cell_m):g}"
        raise OptionError("--source", "library", f"the built-in scenarios are on the paper's {paper} m grid: use "
                                                 f"--cell-m {paper}")
    return [b.load() for b in BUILTINS]


def spread(scenarios: list[Scenario], count: int | None) -> list[Scenario]:
    """At most ``count`` of ``scenarios``, evenly spaced through them in their order (a quick look at a whole
    space or library, not its first corner); all of them when ``count`` is None or not smaller."""
    if count is None or count >= len(scenarios):
        return scenarios
    return [scenarios[i * len(scenarios) // count] for i in range(count)]


# -- one scenario's check (what a worker runs) -------------------------------------------------------
def scenario_key(scenario: Scenario) -> str:
    return json.dumps(scenario_to_dict(scenario), sort_keys=True)


def check_scenario(scenario: Scenario, properties: Sequence[PropertyName], engines: Sequence[str],
                   timeout_s: float | None) -> dict[str, Any]:
    """Every property's verdict on ``scenario``, the runs' latencies and the rules exercised, as a record."""
    runs = Runs(scenario, Limits(timeout_s=timeout_s))
    verdicts = {}
    for name in properties:
        outcome = PROPERTIES[name].verdict(scenario, runs, engines)
        verdicts[name.value] = [outcome.verdict.value, outcome.detail]
    reference = next((r for r in runs.made() if r.key.engine == "interpreter" and r.answer is not None), None)
    first_has_plan = None
    if reference is not None and reference.answer is not None and reference.answer.stages:
        first_has_plan = reference.answer.stages[0][1] is Status.PLAN
    return {"key": scenario_key(scenario), "scenario": scenario_to_dict(scenario), "verdicts": verdicts,
            "ms": {r.key.label: round(r.ms, 3) for r in runs.made()},
            "statuses": {r.key.label: (r.status.value if r.status else "error") for r in runs.made()},
            "rules": [] if scenario.sound is not None else sorted(rules_exercised(scenario, first_has_plan))}


def check_batch(scenarios: list[dict[str, Any]], properties: list[str], engines: list[str], timeout_s: float | None,
                report: Callable[[int], None] | None = None) -> list[dict[str, Any]]:
    """``check_scenario`` over a batch given as scenario files' tables (picklable: a worker's job)."""
    names = [PropertyName(p) for p in properties]
    done = []
    for data in scenarios:
        done.append(check_scenario(scenario_from_dict(data), names, engines, timeout_s))
        if report is not None:
            report(1)
    return done


# -- the campaign ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Campaign:
    """What a campaign checks; its JSON form is the key its records are kept under."""

    source: str
    properties: tuple[PropertyName, ...]
    engines: tuple[str, ...]
    cell_m: float = float(PAPER_GRID.cell_m)
    horizon: int | None = None
    timeout_s: float | None = 10.0
    space: str | None = None
    seed: int | None = None
    #: The sound model's assumptions every scenario is checked under (None: the paper's rules; ``DRAWN``: the
    #: hypothesis source draws them with each scenario, ``ci.conformance.hypo.BOUND_CHOICES``).
    sound: Sound | str | None = None
    #: At most this many scenarios (None: every one the source gives; ``spread`` picks them).
    count: int | None = None
    #: Under the sound model, the commitment semantics (``spec.escapes``) instead of whole plans: its default
    #: commitment, or one drawn with each scenario by the hypothesis source (``ci.conformance.hypo.commitments``).
    commit: bool = False

    def key(self) -> dict[str, Any]:
        key = {"source": self.source, "properties": [p.value for p in self.properties], "engines": list(self.engines),
               "cell_m": self.cell_m, "horizon": self.horizon, "timeout_s": self.timeout_s, "space": self.space,
               "seed": self.seed}
        if self.sound is not None:  # a paper campaign's key is what it always was: its records stay resumable
            key["model"] = "sound"
            key["bounds"] = self.sound if isinstance(self.sound, str) else sound_to_table(self.sound)
        if self.count is not None:  # likewise: a campaign of every scenario keeps its key
            key["count"] = self.count
        if self.commit:  # and a campaign of whole plans
            key["semantics"] = "commit"
        return key

    @property
    def semantics(self) -> Semantics:
        """The semantics the campaign holds the engines to (the paper's rules: whole plans)."""
        return Semantics.COMMIT if self.commit else Semantics.WHOLE

    def with_model(self, scenario: Scenario) -> Scenario:
        """``scenario`` under the campaign's model (a drawn one keeps its own bounds), under its semantics."""
        if not isinstance(self.sound, Sound):
            return scenario
        return replace(scenario, sound=replace(self.sound, commitment=COMMIT) if self.commit else self.sound)


DRAWN = "drawn with each scenario"


def check_resumable(log: Path, campaign: Campaign) -> None:
    """Refuse to resume, into the records of ``log``, a campaign that differs from one recorded there only in its
    model or bounds: its verdicts would sit beside ones made under other assumptions, in one summary. The message
    names the difference."""
    key = campaign.key()
    plain = {k: v for k, v in key.items() if k not in ("model", "bounds")}
    for record in read_records(log):
        other = record.get("campaign")
        if not isinstance(other, dict) or other == key:
            continue
        if {k: v for k, v in other.items() if k not in ("model", "bounds")} != plain:
            continue
        ours, theirs = key.get("bounds"), other.get("bounds")
        option = "--bounds" if ours is not None and theirs is not None else "--model"
        value = ("sound" if option == "--model" else campaign.sound.bounds.name if isinstance(campaign.sound, Sound)
                 else str(campaign.sound)) if campaign.sound is not None else "paper"
        raise OptionError(option, value, f"{log} holds this campaign under other assumptions ("
                                         f"{_difference(ours, theirs)}): resume it with the same model and bounds, "
                                         f"or start again with --fresh or another --out")


def _assumptions(bounds: object) -> str:
    if bounds is None:
        return "the paper's rules"
    if isinstance(bounds, dict):
        return "the sound model, " + ", ".join(f"{k} {v}" for k, v in bounds.items())
    return f"the sound model, bounds {bounds}"


def _difference(ours: object, theirs: object) -> str:
    """How the recorded bounds (``theirs``) differ from this campaign's, key by key; a key a record lacks was not
    recorded by the version that wrote it (e.g. ``latency_s``, added since)."""
    def value(bounds: dict[str, Any], key: str) -> str:
        return str(bounds[key]) if key in bounds else "not recorded"

    if isinstance(ours, dict) and isinstance(theirs, dict):
        changed = [f"{k} {value(theirs, k)} there, {value(ours, k)} here" for k in dict.fromkeys([*theirs, *ours])
                   if theirs.get(k) != ours.get(k) or (k in theirs) != (k in ours)]
        return "; ".join(changed)
    return f"{_assumptions(theirs)} there, {_assumptions(ours)} here"


def recorded(log: Path, campaign: Campaign) -> dict[str, dict[str, Any]]:
    """The verdicts an earlier run of the same campaign recorded, by scenario key (records of one scenario merged:
    the hypothesis source writes one per property)."""
    key = campaign.key()
    merged: dict[str, dict[str, Any]] = {}
    for record in read_records(log):
        result = record.get("result")
        if record.get("campaign") != key or not isinstance(result, dict) or "key" not in result:
            continue
        if result["key"] in merged:
            kept = merged[result["key"]]
            for part in ("verdicts", "ms", "statuses"):
                kept[part] = {**kept[part], **result[part]}
        else:
            merged[result["key"]] = result
    return merged


def run_sweep(campaign: Campaign, scenarios: Iterable[Scenario], out: Path, executor: ExecutorChoice,
              on_result: Callable[[dict[str, Any], bool], None] | None = None,
              on_checked: Callable[[int], None] | None = None) -> list[dict[str, Any]]:
    """Check every scenario not already recorded, appending each verdict as it is decided; every result, in the
    scenarios' order. ``on_result(result, resumed)`` after each; ``on_checked(n)`` as a worker progresses."""
    with campaign_lock(out):
        return _sweep(campaign, scenarios, out, executor, on_result, on_checked)


def _sweep(campaign: Campaign, scenarios: Iterable[Scenario], out: Path, executor: ExecutorChoice,
           on_result: Callable[[dict[str, Any], bool], None] | None,
           on_checked: Callable[[int], None] | None) -> list[dict[str, Any]]:
    log = out / VERDICTS_FILE
    check_resumable(log, campaign)
    scenarios = [campaign.with_model(s) for s in scenarios]
    done = recorded(log, campaign)
    ordered = [scenario_key(s) for s in scenarios]
    todo: list[dict[str, Any]] = []
    seen = set()
    for key in ordered:
        if key in done:
            if on_result:
                on_result(done[key], True)
        elif key not in seen:
            todo.append(json.loads(key))
        seen.add(key)
    batches = [todo[i:i + BATCH] for i in range(0, len(todo), BATCH)]
    jobs = [(batch, [p.value for p in campaign.properties], list(campaign.engines), campaign.timeout_s)
            for batch in batches]
    with (open_for_append(log) as lines,
          contextlib.closing(run_jobs(check_batch, jobs, executor, on_checked)) as finished):
        for _, results in finished:
            for result in results:
                append(lines, {"campaign": campaign.key(), "result": result})
                done[result["key"]] = result
                if on_result:
                    on_result(result, False)
    return [done[key] for key in dict.fromkeys(ordered)]


# -- the summary -------------------------------------------------------------------------------------
@dataclass(slots=True)
class Summary:
    """Per property: checked, held, failed, incomplete; per run: latency; per cell size and rule: scenarios that
    exercised it, and the rules of the coverage target that none did."""

    target: CoverageTarget = CoverageTarget.NONE
    cell_m: float = float(PAPER_GRID.cell_m)  # the campaign's: its target is judged there even with no scenario
    scenarios: int = 0
    verdicts: dict[str, Counter[str]] = field(default_factory=dict)
    ms: dict[str, list[float]] = field(default_factory=dict)
    rules: dict[float, Counter[str]] = field(default_factory=dict)  # cell size (m) -> rule -> scenarios
    failures: dict[str, list[dict[str, Any]]] = field(default_factory=dict)  # property -> failing results
    paper: bool = True  # rule coverage names the paper model's rules: a sound-model campaign shows none

    def add(self, result: dict[str, Any]) -> None:
        self.scenarios += 1
        for name, (verdict, _detail) in result["verdicts"].items():
            self.verdicts.setdefault(name, Counter())[verdict] += 1
            if verdict != Verdict.HELD.value:
                self.failures.setdefault(name, []).append(result)
        for label, ms in result["ms"].items():
            self.ms.setdefault(label, []).append(ms)
        cell_m = float(result["scenario"].get("cell_m", self.cell_m))
        self.rules.setdefault(cell_m, Counter()).update(result["rules"])

    def __post_init__(self) -> None:
        self.rules.setdefault(self.cell_m, Counter())

    @property
    def all_held(self) -> bool:
        return all(set(c) <= {Verdict.HELD.value} for c in self.verdicts.values())

    @property
    def any_failed(self) -> bool:
        """Whether a property failed somewhere (not merely could not be decided)."""
        return any(Verdict.FAILED.value in c for c in self.verdicts.values())

    def coverage(self) -> dict[str, dict[str, int]]:
        """Per cell size ("21 m"), every rule that can occur there and how many scenarios exercised it."""
        if not self.paper:
            return {}
        return {f"{cell_m:g} m": {rule: counts[rule] for rule in rules_on(grid_for(cell_m))}
                for cell_m, counts in sorted(self.rules.items(), reverse=True)}

    def missed(self) -> list[str]:
        """The target's rules no scenario exercised, as "rule at N m" (empty: the target is met)."""
        return [f"{rule} at {cell_m:g} m" for cell_m, counts in sorted(self.rules.items(), reverse=True)
                for rule in self.target.rules(grid_for(cell_m)) if not counts[rule]]

    def latency(self) -> dict[str, dict[str, float]]:
        return {label: {"n": len(ms), "median_ms": round(float(np.median(ms)), 2),
                        "p99_ms": round(float(np.percentile(ms, 99)), 2)} for label, ms in self.ms.items()}

    def to_json(self, campaign: Campaign, reproducers: list[dict[str, Any]]) -> dict[str, Any]:
        return {"campaign": campaign.key(), "scenarios": self.scenarios,
                "properties": {name: {"checked": sum(c.values()), "held": c[Verdict.HELD.value],
                                      "failed": c[Verdict.FAILED.value], "incomplete": c[Verdict.INCOMPLETE.value]}
                               for name, c in self.verdicts.items()},
                "latency": self.latency(),
                "rule_coverage": self.coverage(),
                "coverage_target": {"target": self.target.value, "missed": self.missed()},
                "reproducers": reproducers}


def write_reports(data: dict[str, Any], summary: Summary, campaign: Campaign, out: Path) -> list[Path]:
    """``summary.json`` and ``summary.md`` (from ``data``, the summary's JSON form) and ``junit.xml`` in ``out``."""
    paths = [out / "summary.json", out / "summary.md", out / "junit.xml"]
    paths[0].write_text(json.dumps(data, indent=1))
    paths[1].write_text(markdown(data))
    paths[2].write_bytes(junit(summary, campaign))
    return paths


def _sound_header(campaign: dict[str, Any]) -> str:
    """The sound model's bounds and the semantics the campaign held the engines to: its own key (``Campaign.key``),
    not the bounds' table, whose ``semantics`` is the model's before the campaign applies its own."""
    bounds = campaign["bounds"]
    if isinstance(bounds, dict):
        bounds = {k: v for k, v in bounds.items() if k != "semantics"}
    semantics = campaign.get("semantics", Semantics.WHOLE.value)
    return f"the sound model, bounds {bounds}, semantics {semantics}."


def markdown(data: dict[str, Any]) -> str:
    c = data["campaign"]
    lines = ["# Cross-validation", "",
             f"Source {c['source']}" + (f" ({c['space']})" if c["space"] else "") + (
                 f", seed {c['seed']}" if c["seed"] is not None else "") + (
                 f", at most {c['count']} (--count)" if c.get("count") else "")
             + f"; engines {', '.join(c['engines'])}; {data['scenarios']} scenarios; cell {c['cell_m']:g} m; "
             + (_sound_header(c) if c.get("model") == "sound" else "the paper's rules."), "",
             "| property | checked | held | failed | incomplete |", "|---|---|---|---|---|"]
    lines += [f"| {name} | {v['checked']} | {v['held']} | {v['failed']} | {v['incomplete']} |"
              for name, v in data["properties"].items()]
    lines += ["", "| run | n | median ms | p99 ms |", "|---|---|---|---|"]
    lines += [f"| {label} | {v['n']} | {v['median_ms']} | {v['p99_ms']} |" for label, v in data["latency"].items()]
    for cell, rules in data["rule_coverage"].items():
        lines += ["", f"## Rule coverage at {cell} (scenarios that exercised each rule)", "", "| rule | scenarios |",
                  "|---|---|"]
        lines += [f"| {rule} | {n} |" for rule, n in rules.items()]
    target = data["coverage_target"]
    if target["target"] != CoverageTarget.NONE.value:
        lines += ["", f"Coverage target `{target['target']}`: "
                  + ("met." if not target["missed"] else "**missed**: no scenario exercised "
                     + "; ".join(target["missed"]) + ".")]
    if data["reproducers"]:
        lines += ["", "## Reproducers", ""]
        lines += [f"- {r['property']}: `{r['scenario_file']}` ({r['detail']}); test `{r['test_file']}`"
                  for r in data["reproducers"]]
    return "\n".join(lines) + "\n"


def junit(summary: Summary, campaign: Campaign) -> bytes:
    """One test case per property, failed when any scenario failed it (the first failures as its message)."""
    suite = ElementTree.Element("testsuite", name=f"crossval-{campaign.source}",
                                tests=str(len(summary.verdicts)),
                                failures=str(sum(1 for c in summary.verdicts.values() if c[Verdict.FAILED.value])),
                                errors=str(sum(1 for c in summary.verdicts.values()
                                               if c[Verdict.INCOMPLETE.value] and not c[Verdict.FAILED.value])))
    if summary.target is not CoverageTarget.NONE:
        suite.set("tests", str(len(summary.verdicts) + 1))
        case = ElementTree.SubElement(suite, "testcase", classname="crossval", name=f"coverage-{summary.target.value}")
        if summary.missed():
            suite.set("failures", str(int(suite.get("failures", "0")) + 1))
            ElementTree.SubElement(case, "failure", message="no scenario exercised " + "; ".join(summary.missed()))
    for name, counts in summary.verdicts.items():
        case = ElementTree.SubElement(suite, "testcase", classname="crossval", name=name)
        bad = summary.failures.get(name, [])
        if bad:
            kind = "failure" if counts[Verdict.FAILED.value] else "error"
            first = bad[0]["verdicts"][name]
            element = ElementTree.SubElement(case, kind, message=f"{len(bad)} scenario(s): {first[1]}"[:500])
            element.text = "\n".join(f"{r['key']}: {r['verdicts'][name][1]}" for r in bad[:20])
    return ElementTree.tostring(suite, encoding="utf-8", xml_declaration=True)

