"""The calibration's rule: each kind's rate gives its share of the paper's failures per km, ln 2 / 40.6 km in all."""

from __future__ import annotations

import math
from collections import Counter

import pytest

from ci.simulation.calibrate import PAPER_CAUSES, PAPER_MEDIAN_KM, Lethality, rates, refine
from spec.faults import FaultKind


def test_the_rates_give_each_kind_its_share_of_the_paper_failure_rate() -> None:
    measured = [Lethality(FaultKind.FAKE_GAP, 0.05, 100.0, 7300, 350, 7, 0),
                Lethality(FaultKind.GHOST_LEFT, 0.01, 100.0, 74500, 760, 9, 0),
                Lethality(FaultKind.SAME_CELL, 0.05, 100.0, 17200, 840, 1, 12),  # its stops count too
                Lethality(FaultKind.STEERING, 0.001, 100.0, 105800, 120, 120, 0)]
    derived = rates(measured)
    target = math.log(2) / PAPER_MEDIAN_KM
    for m in measured:
        per_km = derived[m.kind] * (m.offered / m.km) * (m.counted / m.started)
        assert per_km == pytest.approx(target * PAPER_CAUSES[m.kind] / sum(PAPER_CAUSES.values()))
    assert derived[FaultKind.STEERING] == pytest.approx(target / 12 / 1058)


def test_refining_scales_each_kind_to_its_share_and_leaves_the_rare_ones() -> None:
    now = {FaultKind.FAKE_GAP: 0.006, FaultKind.GHOST_LEFT: 0.0004, FaultKind.STEERING: 1e-6}
    refined = refine(now, Counter({"fake-gap": 10, "ghost-left": 13, "steering": 1, None: 6}))
    assert refined[FaultKind.FAKE_GAP] == pytest.approx(0.006 * (6 / 12) / (10 / 30))
    assert refined[FaultKind.GHOST_LEFT] == pytest.approx(0.0004 * (3 / 12) / (13 / 30))
    assert refined[FaultKind.STEERING] == 1e-6  # one event: too few to rescale by
