"""A simulation campaign's deviations and containment breaches as histograms, one line per action type or bound.

Both come from the runs' own records: the tolerance check's histogram of the deviation each action added
(``sim.tolerance``: bins of a fixed width in cells of the paper's 21 m grid, the last one everything beyond) and the
containment monitor's first breaches of each run (``sim.containment``: by how much each broke its bound).
"""

from __future__ import annotations

from collections import defaultdict

from ci.report.document import Figure, png_bytes
from sim.report import pyplot
from sim.summary import RunSummary


def deviation_histograms(runs: list[RunSummary], key: str) -> Figure | None:
    """The deviation each action added, per action type, summed over the runs (None when no action was checked)."""
    counts: dict[str, list[int]] = {}
    bin_cells, step, plan = 0.0, 0.0, 0.0
    for run in runs:
        report = run.tolerance
        bin_cells, step, plan = report.bin_cells, report.step_tolerance, report.plan_tolerance
        for action, bins in report.histogram.items():
            total = counts.setdefault(action, [0] * len(bins))
            if len(total) != len(bins):
                return None  # runs recorded with different bins cannot be summed
            counts[action] = [a + b for a, b in zip(total, bins, strict=True)]
    if not counts or bin_cells <= 0:
        return None
    fig, ax = pyplot().subplots(figsize=(8, 3.6))
    for action, bins in sorted(counts.items()):
        edges = [i * bin_cells for i in range(len(bins) + 1)]
        ax.stairs(bins, edges, label=f"{action} ({sum(bins):,} checks)")
    ax.axvline(step, color="k", ls="--", lw=1, label=f"tolerance per action ({step:g})")
    ax.set_yscale("symlog", linthresh=1)
    beyond = (len(next(iter(counts.values()))) - 1) * bin_cells
    ax.set_xlabel(f"deviation added by one action (cells of the paper's grid; bins of {bin_cells:g}; the last bin: "
                  f"beyond {beyond:g})")
    ax.set_ylabel("checks")
    ax.legend(fontsize=7)
    caption = (f"deviation from the model's prediction per action type, every vehicle after every action, all runs, "
               f"in cells of the paper's 21 m grid (tolerance {step:g} per action, {plan:g} per plan: what the paper "
               f"model's tolerance check allows)")
    return Figure(None, caption, png_bytes(fig), f"{key}-deviations")


def breach_histograms(runs: list[RunSummary], key: str) -> Figure | None:
    """How far each recorded containment breach went past its bound, per bound broken (None without breaches)."""
    by_kind: dict[str, list[float]] = defaultdict(list)
    for run in runs:
        for breach in run.containment.breaches:
            by_kind[f"{breach.kind.value}, {'speed (m/s)' if breach.speed else 'position (m)'}"].append(breach.by_m)
    if not by_kind:
        return None
    fig, ax = pyplot().subplots(figsize=(8, 3.6))
    largest = max(max(v) for v in by_kind.values())
    edges = [i * max(largest, 1e-6) / 30 for i in range(31)]
    for kind, sizes in sorted(by_kind.items()):
        ax.hist(sizes, bins=edges, histtype="step", label=f"{kind} ({len(sizes):,})")
    ax.set_xlabel("beyond the bound (m for a position, m/s for a speed)")
    ax.set_ylabel("breaches")
    ax.legend(fontsize=7)
    recorded = sum(len(v) for v in by_kind.values())
    counted = sum(run.containment.count for run in runs)
    caption = (f"containment breaches by how far they went past the bound they broke, per bound: the {recorded:,} "
               f"recorded of {counted:,} counted (each run records its first breaches in full)")
    return Figure(None, caption, png_bytes(fig), f"{key}-breaches")
