"""What a drive leaves behind: a space-time plot of the measured paths with the predicted cells over them."""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from spec.constants import AV_CELL, SEGMENT_M


def plot_trace(trace: Path, png: Path, max_points: int = 4000) -> Path:
    """Distance of every vehicle from the AV over time (dots: measured), and the cells the model predicted (x)."""
    records = [json.loads(line) for line in trace.read_text().splitlines()[:max_points]]
    fig, ax = plt.subplots(figsize=(11, 5))
    for r in records:
        measured = [d for d in r["traffic_dx_m"] if -120 <= d <= 400]
        ax.scatter([r["t_s"]] * len(measured), measured, s=3, c="tab:blue")
        for lane, colour in (("left_lane", "tab:green"), ("right_lane", "tab:red")):
            predicted = [(c - AV_CELL) * SEGMENT_M for c in r["predicted"][lane]]
            ax.scatter([r["t_s"]] * len(predicted), predicted, s=14, marker="x", c=colour)
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xlabel("simulated time (s)")
    ax.set_ylabel("distance ahead of the AV (m)")
    ax.set_title("measured (dots) vs predicted cell centres (x: green left lane, red oncoming)")
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return png
