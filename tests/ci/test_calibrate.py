"""The calibration's rule: each kind's rate gives its share of the paper's failures per km, ln 2 / 40.6 km in all."""

from __future__ import annotations

import math

import pytest

from ci.calibrate import PAPER_CAUSES, PAPER_MEDIAN_KM, Lethality, rates
from spec.faults import FaultKind


def test_the_rates_give_each_kind_its_share_of_the_paper_failure_rate() -> None:
    measured = [Lethality(FaultKind.FAKE_GAP, 0.05, 100.0, 7300, 350, 7, 0),
                Lethality(FaultKind.GHOST_LEFT, 0.01, 100.0, 74500, 760, 9, 0),
                Lethality(FaultKind.SAME_CELL, 0.05, 100.0, 17200, 840, 0, 12),  # only stops: calibrated on them
                Lethality(FaultKind.STEERING, 0.001, 100.0, 105800, 120, 120, 0)]
    derived = rates(measured)
    target = math.log(2) / PAPER_MEDIAN_KM
    for m in measured:
        per_km = derived[m.kind] * (m.offered / m.km) * (m.counted / m.started)
        assert per_km == pytest.approx(target * PAPER_CAUSES[m.kind] / sum(PAPER_CAUSES.values()))
    assert derived[FaultKind.STEERING] == pytest.approx(target / 12 / 1058)
