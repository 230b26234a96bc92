"""What a drive leaves behind: a space-time plot of the measured positions with the predicted cells over them (the
paper model's; the sound model's sets are intervals, and its records predict no cells)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from spec.actions import ACTION_RULES, Action
from spec.grid import Grid

LANES = (("left_lane", "tab:green", "left lane"), ("right_lane", "tab:red", "oncoming"))
SHOWN_M = (-120.0, 400.0)
ACTION_LETTER = {"accelerate": "A", "drive": "D", "brake": "B", "right_lane_change": "R", "left_lane_change": "L"}
#: The letter of a record with no action: a fallback's or a minimal-risk manoeuvre's control (the sound model).
FALLBACK_LETTER = "F"


def _duration_s(record: dict[str, Any]) -> float:
    """How long a record's action ran: as recorded (the sound model's records), else its rule's duration."""
    if "duration_s" in record:
        return float(record["duration_s"])
    return float(ACTION_RULES[Action(record["action"])].duration_s)


def pyplot() -> Any:
    """matplotlib's pyplot on the Agg backend (files only, never a window), imported when a figure is first drawn: a
    command that draws none (bad input above all) does not pay the half second it takes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_trace(trace: Path, png: Path, grid: Grid, window_s: float = 300.0) -> Path:
    """Distance of every vehicle from the AV over the last ``window_s`` of the drive (for a failed drive: the
    lead-up to the failure): measured at the end of each action (dots) and as the model predicted (x)."""
    records = [json.loads(line) for line in trace.read_text().splitlines() if line.strip()]
    end_s = records[-1]["t_s"] if records else 0.0
    shown = [r for r in records if r["t_s"] >= end_s - window_s]
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(11, 5))
    for lane, colour, label in LANES:
        measured = [(r["t_s"], d) for r in shown for d in r["measured_dx_m"][lane] if SHOWN_M[0] <= d <= SHOWN_M[1]]
        predicted = [(r["t_s"], (c - grid.av_cell) * grid.cell) for r in shown if r["predicted"]
                     for c in r["predicted"][lane] if SHOWN_M[0] <= (c - grid.av_cell) * grid.cell <= SHOWN_M[1]]
        if measured:
            ts, ds = zip(*measured)
            ax.scatter(ts, ds, s=8, c=colour, alpha=0.45, label=f"{label}: measured")
        if predicted:
            ts, ds = zip(*predicted)
            ax.scatter(ts, ds, s=30, marker="x", c=colour, label=f"{label}: predicted cell centre")
    ax.axhline(0, color="k", lw=0.8)
    for r in shown:  # the AV's lane and action: a band along the bottom, one letter per action at its end
        right = r["av"]["y_m"] < 0
        ax.axvspan(r["t_s"] - _duration_s(r), r["t_s"], ymin=0.0, ymax=0.03, color="tab:red" if right else "tab:green",
                   alpha=0.6, lw=0)
        letter = FALLBACK_LETTER if r["action"] is None else ACTION_LETTER.get(r["action"], "?")
        ax.annotate(letter, (r["t_s"], 0.035), xycoords=("data", "axes fraction"), fontsize=6, ha="right")
    ax.set_xlabel("simulated time (s); bottom band: the AV's lane (green its own, red the oncoming one) and its "
                  "actions (A accelerate, D drive, B brake, R/L lane change, F fallback or minimal-risk manoeuvre)",
                  fontsize=8)
    ax.set_ylabel("distance ahead of the AV (m)")
    span_s = end_s - shown[0]["t_s"] if shown else 0.0
    what = "measured vs predicted" if any(r["predicted"] for r in shown) else \
        "measured (the sound model predicts no cells)"
    ax.set_title(f"{trace.stem}: the last {span_s:.0f} s of the drive, {what} after every action")
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return png
