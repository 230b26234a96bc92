"""Read campaign output folders (crossval, simulate, audit, mutation) into report sections, and the headline.

A folder is recognised by the file its command writes last (``summary.json``, ``runs.jsonl``, ``audit.json``,
``mutation.json``); a folder with none of them is searched one level down (``overtake report out`` reads every
campaign CI ran). What cannot be read is skipped with its reason, never guessed at.
"""

from __future__ import annotations

import contextlib
import json
import os
import stat
from collections import Counter
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from ci.audit.campaign import figure, plot_tradeoffs, record_label, tradeoffs
from ci.report.closest import closest_figures, gap_order
from ci.report.document import Figure, Report, Section, Table, from_rich, png_bytes
from ci.report.histograms import breach_histograms, deviation_histograms
from ci.report.road import reproducer_drawing
from sim.paper import MEDIAN_KM
from sim.summary import RunSummary
from sim.tables import deviations_table, faults_table, paper_table, runs_table, totals_table

CAMPAIGN_LOGS = {"simulate": "runs.jsonl", "audit": "audit.jsonl"}  # the runs whose closest calls are drawn
MAX_SPACETIME_PLOTS = 4  # per simulation folder: the page stays readable (the rest are named)
MAX_WORST = 12  # closest calls listed per audit
MAX_DRAWN_REPRODUCERS = 3  # per crossval folder: each drawing runs its property's engines again (the rest: traces)


class Unreadable(Exception):
    """A campaign file that exists but cannot be read as its command writes it."""


def rate(count: float, km: float, per: float = 1000.0) -> str:
    """``count`` per ``per`` km, or "-" where no km were driven (a rate of nothing is undefined, never "nan")."""
    return figure(per * count / km if km > 0 else None)


def number(value: Any, digits: int = 2) -> str:
    """A figure from a JSON record as text (``ci.audit.campaign.figure`` for a float: "-" for a missing or undefined
    one)."""
    return figure(value, digits) if value is None or isinstance(value, float) else str(value)


#: The largest campaign file read (a 1,000 km campaign's runs.jsonl is tens of megabytes).
MAX_FILE_BYTES = 512 * 2**20


def check_file(path: Path) -> None:
    """``path`` is a regular file of at most ``MAX_FILE_BYTES``: never a device, a pipe, or a file without end."""
    try:
        info = path.stat()
    except OSError as error:
        raise Unreadable(f"{path.name}: {error.strerror or error}") from None
    if not stat.S_ISREG(info.st_mode):
        raise Unreadable(f"{path.name}: not a regular file")
    if info.st_size > MAX_FILE_BYTES:
        raise Unreadable(f"{path.name}: {info.st_size:,} bytes, more than the {MAX_FILE_BYTES:,} read")


def _readable(path: Path) -> bool:
    """Whether ``path`` is a file ``check_file`` lets the report read (a plot or a trace: left out if not)."""
    try:
        check_file(path)
    except Unreadable:
        return False
    return True


def _figure(path: Path, caption: str) -> Figure | None:
    """The PNG at ``path``, read now (None when it cannot be: the report goes on without it)."""
    if not _readable(path):
        return None
    try:
        return Figure(path, caption, path.read_bytes())
    except OSError:
        return None


def _json(path: Path) -> Any:
    check_file(path)
    try:
        return json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError) as error:
        raise Unreadable(f"{path.name}: {type(error).__name__}: {str(error)[:200]}") from None


# -- crossval -----------------------------------------------------------------------------------------------------
def crossval_section(folder: Path, key: str) -> Section:
    data = _json(folder / "summary.json")
    try:
        campaign, properties, latency = data["campaign"], data["properties"], data["latency"]
        model = "the sound model" if campaign.get("model") == "sound" else "the paper's rules"
        section = Section(key, f"Conformance: {campaign['source']} source, {model}", str(folder))
        counts = Counter[str]()
        for verdicts in properties.values():
            counts.update({k: int(verdicts[k]) for k in ("checked", "held", "failed", "incomplete")})
        section.facts = {"scenarios": int(data["scenarios"]), "failed": counts["failed"],
                         "incomplete": counts["incomplete"], "model": model, "cell_m": float(campaign["cell_m"]),
                         "failed_properties": sorted(n for n, v in properties.items() if v["failed"])}
        section.findings.append(
            f"{data['scenarios']} scenarios, engines {', '.join(campaign['engines'])}, cell {campaign['cell_m']:g} m: "
            + ("every property held on every scenario" if counts["failed"] == 0 and counts["incomplete"] == 0 else
               f"{counts['failed']} failed and {counts['incomplete']} incomplete of {counts['checked']} checks"))
        columns = ("checked", "held", "failed", "incomplete")
        section.tables.append(Table("properties", ("property", *columns), tuple(
            (name, *(str(v[k]) for k in columns)) for name, v in properties.items())))
        section.tables.append(Table("latency per engine run (whole pipeline)", ("run", "n", "median ms", "p99 ms"),
                                    tuple((run, str(v["n"]), number(v["median_ms"]), number(v["p99_ms"]))
                                          for run, v in latency.items())))
        for grid, rules in data.get("rule_coverage", {}).items():
            if rules:
                section.tables.append(Table(f"rule coverage at {grid} (scenarios that exercised each rule)",
                                            ("rule", "scenarios"), tuple((r, str(n)) for r, n in rules.items())))
        missed = data.get("coverage_target", {}).get("missed", [])
        if missed:
            section.findings.append(f"rules the campaign was asked to cover and never exercised: {', '.join(missed)}")
        for number_, repro in enumerate(data.get("reproducers", []), 1):
            _reproducer(section, folder, repro, number_)
    except (KeyError, TypeError, ValueError, AttributeError) as error:
        raise Unreadable(f"summary.json: not a crossval summary ({type(error).__name__}: {error})") from None
    return section


def _reproducer(section: Section, folder: Path, repro: dict[str, Any], number_: int) -> None:
    """A failure's reproducer: its detail, the files, the traces as the command wrote them and drawn as the road."""
    section.findings.append(f"{repro['property']} failed: {repro['detail']} (reproducer "
                            f"{Path(repro['scenario_file']).name}, {repro['vehicles']} vehicles, shrunk in "
                            f"{repro['shrink_checks']} checks)")
    repro_dir = folder / "repro"
    traces = repro_dir / Path(repro["traces_file"]).name
    if _readable(traces):
        with contextlib.suppress(OSError, UnicodeDecodeError):  # the report goes on without them
            section.texts.append((f"{repro['property']} reproducer {number_}: the engines' traces side by side",
                                  traces.read_text()))
    if number_ > MAX_DRAWN_REPRODUCERS:  # each drawing runs the property's engines again
        return
    scenario_file = repro_dir / Path(repro["scenario_file"]).name
    drawing = reproducer_drawing(scenario_file, f"{section.key}-repro-{number_}", repro["property"])
    if drawing is not None:
        section.drawings.append(drawing)


# -- simulate -----------------------------------------------------------------------------------------------------
def simulation_section(folder: Path, key: str) -> Section:
    from ci.shared.records import read_records

    check_file(folder / "runs.jsonl")
    try:
        records = list(read_records(folder / "runs.jsonl"))
    except (OSError, UnicodeDecodeError, RecursionError) as error:
        raise Unreadable(f"runs.jsonl: {type(error).__name__}: {str(error)[:200]}") from None
    try:
        return _simulation(folder, key, records)
    except (KeyError, TypeError, ValueError, AttributeError, ZeroDivisionError) as error:
        raise Unreadable(f"runs.jsonl: not a simulate record ({type(error).__name__}: {error})") from None


def _simulation(folder: Path, key: str, records: list[dict[str, Any]]) -> Section:
    configs = {json.dumps(r["campaign"], sort_keys=True): r["campaign"] for r in records}
    runs = sorted((RunSummary.from_json(r["run"]) for r in records), key=lambda s: s.seed)
    if not runs:
        raise Unreadable("runs.jsonl: no run recorded yet")
    config = next(iter(configs.values()))
    if not isinstance(config, dict):
        raise TypeError(f"a campaign record of {type(config).__name__}")
    model = config.get("model", "paper")
    section = Section(key, f"Simulation: {model} model, {config['traffic']} traffic, {config['sensor']} sensing, "
                           f"{config['cell_m']:g} m cells", str(folder))
    if len(configs) > 1:
        section.findings.append(f"runs.jsonl holds {len(configs)} configurations: the tables add them up")
    km = sum(r.km for r in runs)
    collisions = sum(len(r.collisions) for r in runs)
    overtakes = sum(r.overtakes for r in runs)
    section.findings.append(
        f"{len(runs)} runs, {km:.1f} km, {overtakes} overtakes ({overtakes / km:.2f} per km); " if km > 0 else
        f"{len(runs)} runs, no km driven; ")
    section.findings[-1] += (f"{collisions} collision(s) ({rate(collisions, km)} per 1,000 km), "
                             f"{sum(len(r.planner_failures) for r in runs)} decision(s) without a plan; faults "
                             f"{config.get('faults') or 'none'}, tracking {'on' if config.get('tracking') else 'off'}")
    section.facts = {"km": km, "collisions": collisions, "overtakes": overtakes, "runs": len(runs)}
    sensing_only = bool(config.get("until_sensing_failure"))
    if config.get("until_failure") or sensing_only:
        failed = [r for r in runs if r.ended(sensing_only) is not None]
        kms = sorted(r.km for r in runs)
        median = kms[len(kms) // 2] if len(kms) % 2 else (kms[len(kms) // 2 - 1] + kms[len(kms) // 2]) / 2
        censored = len(runs) - len(failed)
        what = "a sensing-caused failure" if sensing_only else "failure"
        section.findings.append(
            f"until {what} (cap {config['km']:g} km): {len(failed)} of {len(runs)} runs failed, median "
            f"{median:.1f} km{' or more' if censored * 2 >= len(runs) else ''} ({censored} reached the cap); "
            f"the paper: a failure every {MEDIAN_KM} km (median)")
        section.facts["until_failure"] = section.findings[-1]
    tables = [totals_table(runs), runs_table(runs), deviations_table(runs)]
    if config.get("until_failure") or sensing_only:
        tables.append(paper_table(runs, float(config["km"]), sensing_only))
    if config.get("faults"):
        tables.append(faults_table(runs))
    section.tables += [from_rich(t) for t in tables]
    section.figures += [f for f in (deviation_histograms(runs, key), breach_histograms(runs, key)) if f is not None]
    plots = sorted((p for p in folder.glob("spacetime-seed*.png") if p.stem.removeprefix("spacetime-seed").isdigit()
                    and _readable(p)), key=lambda p: int(p.stem.removeprefix("spacetime-seed")))
    section.figures += [f for p in plots[:MAX_SPACETIME_PLOTS] if (f := _figure(
        p, f"seed {p.stem.removeprefix('spacetime-seed')}: measured positions and the cells the planner predicted (the "
        "last minutes of the run)")) is not None]
    if len(plots) > MAX_SPACETIME_PLOTS:
        section.findings.append(f"{len(plots) - MAX_SPACETIME_PLOTS} more space-time plots in {folder}")
    return section


# -- audit --------------------------------------------------------------------------------------------------------
AUDIT_HEADERS = ("cell m", "traffic", "sensing", "model", "km", "overtakes /km", "collisions /1,000 km",
                 "inside / after", "near misses /1,000 km", "inside / after", "breaches /1,000 km")


def _inside_after(row: dict[str, Any], kind: str) -> str:
    attributed, km = row.get("attributed", {}), float(row["km"])
    return " / ".join(rate(attributed.get(f"{kind} {side}", 0), km) for side in ("inside", "after"))


def audit_section(folder: Path, key: str) -> Section:
    data = _json(folder / "audit.json")
    try:
        rows, costs, settings = data["combinations"], data["planning_cost"], data["settings"]
        section = Section(key, "Audit: the grid abstraction against traffic and sensing that do not keep to it",
                          str(folder))
        section.findings.append(f"{len(rows)} combinations, seeds {settings.get('seeds')}, "
                                f"{sum(float(r['km']) for r in rows):.1f} km in all")
        section.facts = {"models": _audit_findings(rows), "tradeoffs": tradeoffs(rows)}
        section.findings += section.facts["models"]
        section.tables.append(Table("collisions, near misses and containment per combination", AUDIT_HEADERS, tuple(
            (f"{r['cell_m']:g}", r["traffic"], r["sensing"], record_label(r), f"{r['km']:.1f}",
             number(r["overtakes"] / r["km"] if r["km"] else None), rate(r["collisions"], r["km"]),
             _inside_after(r, "contact"), rate(r["near_misses"], r["km"]), _inside_after(r, "near_miss"),
             rate(sum(r.get("breaches", {}).values()), r["km"])) for r in rows),
            "inside / after: attributed inside the model's assumptions (a soundness failure) or after one broke"))
        kinds = sorted({k for r in rows for k in r.get("breaches", {})})
        if kinds:
            section.tables.append(Table(
                "breaches of the assumptions per 1,000 km, by kind", ("cell m", "traffic", "sensing", "model",
                                                                       *kinds),
                tuple((f"{r['cell_m']:g}", r["traffic"], r["sensing"], record_label(r),
                       *(rate(r.get("breaches", {}).get(k, 0), r["km"]) for k in kinds)) for r in rows),
                "measured from the truth against the world's bounds under both models (sim.containment)"))
        section.tables.append(Table("planning latency per engine on the snapshots the planner saw",
                                    ("cell m", "model", "engine", "n", "median ms", "p99 ms", "incomplete"),
                                    tuple((f"{c['cell_m']:g}", c["model"], c["engine"], str(c["n"]),
                                           number(c["median_ms"]), number(c["p99_ms"]), str(c["incomplete"]))
                                          for c in costs)))
        worst = sorted(((r, e) for r in rows for e in r.get("worst", []) if isinstance(e, dict)),
                       key=lambda re: gap_order(re[1]))[:MAX_WORST]
        if worst:
            section.tables.append(Table("the closest calls (collisions first, then the smallest true gaps)",
                                        ("cell m", "traffic", "sensing", "model", "kind", "at km", "true gap m",
                                         "doing", "assumptions"),
                                        tuple((f"{r['cell_m']:g}", r["traffic"], r["sensing"], record_label(r),
                                               e["kind"], number(e["km"], 3), number(e["gap_m"]), e["doing"],
                                               e.get("assumptions") or "-") for r, e in worst)))
    except (KeyError, TypeError, ValueError, AttributeError, ZeroDivisionError) as error:
        raise Unreadable(f"audit.json: not an audit ({type(error).__name__}: {error})") from None
    captions = {"audit-models.png": "collisions and overtakes per km against cell size, one line per model and "
                                    "traffic", "audit-safety.png": "collisions and near misses against cell size",
                "audit-latency.png": "planning latency per engine against cell size"}
    section.figures += [f for name, caption in captions.items() if (f := _figure(folder / name, caption)) is not None]
    return section


def _audit_findings(rows: list[dict[str, Any]]) -> list[str]:
    """Per model: where it collided inside its assumptions (unsound) and after them; its overtakes per km."""
    lines = []
    for model in sorted({record_label(r) for r in rows}):
        mine = [r for r in rows if record_label(r) == model]
        km = sum(float(r["km"]) for r in mine)
        inside = [r for r in mine if r.get("attributed", {}).get("contact inside", 0)]
        after = sum(r.get("attributed", {}).get("contact after", 0) for r in mine)
        overtakes = sum(r.get("overtakes", 0) for r in mine)
        where = "; ".join(f"{r['cell_m']:g} m {r['traffic']} {r['sensing']} "
                          f"({rate(r['attributed']['contact inside'], r['km'])})" for r in inside)
        lines.append(f"{model} model, {km:.1f} km: collisions inside its assumptions in {len(inside)} of {len(mine)} "
                     f"combinations{': ' + where if where else ''}; {after} after an assumption broke; "
                     f"{overtakes / km if km else 0:.2f} overtakes per km")
    return lines


# -- mutation -----------------------------------------------------------------------------------------------------
def mutation_section(folder: Path, key: str) -> Section:
    data = _json(folder / "mutation.json")
    try:
        section = Section(key, "Mutation check: faults planted in the engines' translations", str(folder))
        caught = [v for v in data if v["caught_by"]]
        section.facts = {"caught": len(caught), "mutants": len(data)}
        section.findings.append(f"{len(caught)} of {len(data)} mutants caught"
                                + ("" if len(caught) == len(data) else ": missed " + ", ".join(
                                    v["mutant"] for v in data if not v["caught_by"])))
        section.tables.append(Table("mutants", ("mutant", "caught by", "seconds", "first failing check"), tuple(
            (v["mutant"], v["caught_by"] or ("NO VERDICT (a detector crashed)" if v.get("undecided") else "NOT CAUGHT"),
             f"{v['seconds']:.0f}", v["reproducer"] or "-")
            for v in data)))
    except (KeyError, TypeError, ValueError, AttributeError) as error:
        raise Unreadable(f"mutation.json: not a mutation check ({type(error).__name__}: {error})") from None
    return section


#: What marks a campaign's folder (the file its command writes last), and how it is read.
READERS: dict[str, tuple[str, Callable[[Path, str], Section]]] = {
    "summary.json": ("crossval", crossval_section),
    "runs.jsonl": ("simulate", simulation_section),
    "audit.json": ("audit", audit_section),
    "mutation.json": ("mutation", mutation_section),
}


def _campaign_folders(folders: Iterable[Path], skipped: list[tuple[str, str]]) -> list[tuple[Path, str]]:
    """(folder, marker) for each campaign folder given, or found one level below a folder that is none."""
    found: list[tuple[Path, str]] = []
    for folder in folders:
        marker = _marker(folder)
        if marker is not None:
            found.append((folder, marker))
            continue
        try:
            subs = sorted(p for p in folder.iterdir() if p.is_dir())
        except OSError as error:
            skipped.append((str(folder), f"cannot be listed ({error.strerror or error})"))
            continue
        below = [(sub, m) for sub in subs for m in [_marker(sub)] if m is not None]
        if not below:
            skipped.append((str(folder), "no campaign output in it or one level below (summary.json, runs.jsonl, "
                                         "audit.json or mutation.json)"))
        found += below
    return found


def _marker(folder: Path) -> str | None:
    """The campaign file in ``folder`` that says what it holds (None: none, or a folder that cannot be looked into)."""
    try:
        return next((m for m in READERS if os.path.lexists(folder / m)), None)
    except OSError:
        return None


def collect(folders: Iterable[Path], frames: int = 0) -> Report:
    """The report of every campaign folder in ``folders`` (each checked to be a readable folder by the caller);
    ``frames`` closest calls per simulate or audit folder drawn (``ci.report.closest``)."""
    skipped: list[tuple[str, str]] = []
    found: list[tuple[str, str]] = []
    sections: list[Section] = []
    keys = Counter[str]()
    for folder, marker in _campaign_folders(folders, skipped):
        kind, read = READERS[marker]
        keys[kind] += 1
        try:
            section = read(folder, f"{kind}-{keys[kind]}")
        except Unreadable as error:
            skipped.append((str(folder), str(error)))
            continue
        log = CAMPAIGN_LOGS.get(kind)
        if frames and log is not None and _readable(folder / log):
            figures, notes = closest_figures(folder / log, frames, section.key)
            section.figures += figures
            section.findings += notes
        sections.append(section)
        found.append((str(folder), kind))
    order = {kind: i for i, (kind, _) in enumerate(READERS.values())}
    sections.sort(key=lambda s: order[s.key.rsplit("-", 1)[0]])
    return Report(headline(sections), sections, found, skipped)


def headline(sections: list[Section]) -> Section:
    """The questions a reader comes with, each answered in a line added up from the sections (or said to be
    unanswered)."""
    head = Section("headline", "What the campaigns found", "")
    by_kind: dict[str, list[Section]] = {}
    for s in sections:
        by_kind.setdefault(s.key.rsplit("-", 1)[0], []).append(s)
    answers = {"crossval": ("Do the engines agree?", _agree), "audit": ("Where does the abstraction break?", _breaks),
               "simulate": ("How did the simulated car fare against the paper?", _fared),
               "mutation": ("Does the conformance check catch planted faults?", _caught)}
    for kind, (question, answer) in answers.items():
        mine = by_kind.get(kind, [])
        head.findings.append(f"{question} " + (answer(mine) if mine else f"Not answered: no {kind} output given."))
    audits = by_kind.get("audit", [])
    head.findings.append("What does each model's safety cost in progress? " + (
        _costs(audits) if audits else "Not answered: no audit output given."))
    for i, s in enumerate(audits, 1):  # the headline figure, drawn from each audit's records
        head.figures.append(Figure(None, f"overtakes per km against collisions per 1,000 km, a point per model and "
                                         f"world ({s.source})", png_bytes(plot_tradeoffs(s.facts["tradeoffs"])),
                                   f"headline-tradeoff-{i}"))
    return head


def _costs(sections: list[Section]) -> str:
    return "; ".join(f"{p.model} in {p.traffic} traffic, {p.sensing} sensing: {p.overtakes_per_km:.2f} overtakes "
                     f"per km, {rate(p.collisions, p.km)} collisions per 1,000 km ({p.inside} inside its assumptions)"
                     for s in sections for p in s.facts["tradeoffs"]) + "."


def _agree(sections: list[Section]) -> str:
    scenarios = sum(s.facts["scenarios"] for s in sections)
    failed = [s for s in sections if s.facts["failed"]]
    incomplete = sum(s.facts["incomplete"] for s in sections)
    models = ", ".join(sorted({s.facts["model"] for s in sections}))
    cells = ", ".join(f"{c:g}" for c in sorted({s.facts["cell_m"] for s in sections}, reverse=True))
    where = f"{len(sections)} campaign(s), {scenarios:,} scenarios ({models}; cells {cells} m)"
    if failed:
        return ("No: checks failed in " + "; ".join(f"{s.title} ({', '.join(s.facts['failed_properties'])})"
                                                   for s in failed) + f", of {where}; reproducers below.")
    return f"Yes: every property held on every scenario of {where}" + (
        f"; {incomplete} check(s) incomplete (no verdict)." if incomplete else ".")


def _breaks(sections: list[Section]) -> str:
    return " ".join(f"{'; '.join(s.facts['models'])}." for s in sections)


def _fared(sections: list[Section]) -> str:
    km = sum(s.facts["km"] for s in sections)
    collisions = sum(s.facts["collisions"] for s in sections)
    overtakes = sum(s.facts["overtakes"] for s in sections)
    line = (f"{sum(s.facts['runs'] for s in sections)} run(s), {km:,.1f} km, {overtakes / km if km else 0:.2f} "
            f"overtakes per km, {collisions} collision(s) ({rate(collisions, km)} per 1,000 km).")
    return line + "".join(f" {s.facts['until_failure']}." for s in sections if "until_failure" in s.facts)


def _caught(sections: list[Section]) -> str:
    caught, mutants = (sum(s.facts[k] for s in sections) for k in ("caught", "mutants"))
    return f"{'Yes' if caught == mutants else 'No'}: {caught} of {mutants} mutants caught."
