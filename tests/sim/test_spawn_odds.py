"""The paper's respawn odds, drawn many times with fixed seeds and compared with the odds written out here by hand
(not read back from ``spec.physical``, which the sampler itself reads): oncoming gaps of 8/12/16/20 cells with odds
1/8, 1/4, 1/4, 3/8, and left-lane gaps of 1-4 cells with equal odds, a gap of one barred after three in a row.

Each category's count must lie in its exact binomial acceptance interval at a false-alarm probability of 1e-6
(``scipy.stats.binom.interval``), and the counts together must pass a chi-square goodness of fit at 1e-6: a correct
sampler fails one sample's checks with probability at most 5e-6, and this file's six samples at most 3e-5 (union
bounds); the fixed seeds make every run the same. 100,000 oncoming draws put each category's interval within
0.005-0.008 of its odds, so two odds swapped (a change of 0.125), shifted by one cell or reversed are rejected by a
wide margin (more than 50 standard deviations in some category); two equal odds (1/4, 1/4) swapped change nothing."""

from __future__ import annotations

from collections import Counter
from fractions import Fraction

import numpy as np
import pytest
from scipy.stats import binom, chisquare

from sim.traffic import left_gap_cells, oncoming_gap_cells
from spec.physical import TRAFFIC

SEED = 20261124
ONCOMING_DRAWS, LEFT_DRAWS = 100_000, 20_000
FALSE_ALARM = 1e-6  # per check, for a correct sampler
PAPER_ONCOMING_ODDS = {8: Fraction(1, 8), 12: Fraction(1, 4), 16: Fraction(1, 4), 20: Fraction(3, 8)}
PAPER_LEFT_CELLS, PAPER_MAX_IN_A_ROW = (1, 2, 3, 4), 3


def assert_follows(counts: Counter[int], odds: dict[int, Fraction], draws: int) -> None:
    """Every count within its binomial interval, only the stated values drawn, and a chi-square fit."""
    assert set(counts) <= set(odds), f"drawn outside the stated values: {sorted(set(counts) - set(odds))}"
    for value, p in odds.items():
        low, high = binom.interval(1 - FALSE_ALARM, draws, float(p))
        assert low <= counts[value] <= high, (value, counts[value] / draws, float(p), low / draws, high / draws)
    observed = [counts[value] for value in odds]
    expected = [float(p) * draws for p in odds.values()]
    assert chisquare(observed, expected).pvalue > FALSE_ALARM, (observed, expected)


def test_the_spec_states_the_papers_respawn_rules() -> None:
    assert dict(zip(TRAFFIC.oncoming_gap_cells, TRAFFIC.oncoming_gap_odds, strict=True)) == PAPER_ONCOMING_ODDS
    assert TRAFFIC.left_respawn_cells == PAPER_LEFT_CELLS and TRAFFIC.max_consecutive == PAPER_MAX_IN_A_ROW


def test_oncoming_gaps_have_the_papers_odds_cell_by_cell() -> None:
    rng = np.random.default_rng(SEED)
    counts = Counter(oncoming_gap_cells(rng) for _ in range(ONCOMING_DRAWS))
    assert_follows(counts, PAPER_ONCOMING_ODDS, ONCOMING_DRAWS)


@pytest.mark.parametrize("wrong", [
    {8: Fraction(1, 4), 12: Fraction(1, 8), 16: Fraction(1, 4), 20: Fraction(3, 8)},  # first two swapped
    {8: Fraction(1, 8), 12: Fraction(1, 4), 16: Fraction(3, 8), 20: Fraction(1, 4)},  # last two swapped
    {8: Fraction(3, 8), 12: Fraction(1, 8), 16: Fraction(1, 4), 20: Fraction(1, 4)},  # shifted by one cell
    {8: Fraction(3, 8), 12: Fraction(1, 4), 16: Fraction(1, 4), 20: Fraction(1, 8)},  # reversed
])
def test_the_oncoming_check_rejects_a_sampler_with_wrong_odds(wrong: dict[int, Fraction]) -> None:
    """The check above, applied to draws with the odds a fault would give, fails: it has the power claimed."""
    rng = np.random.default_rng(SEED)
    drawn = rng.choice(list(wrong), size=ONCOMING_DRAWS, p=[float(p) for p in wrong.values()])
    with pytest.raises(AssertionError):
        assert_follows(Counter(int(g) for g in drawn), PAPER_ONCOMING_ODDS, ONCOMING_DRAWS)


@pytest.mark.parametrize("run", [0, 1, 2])
def test_left_gaps_have_equal_odds_while_fewer_than_three_are_in_a_row(run: int) -> None:
    rng = np.random.default_rng(SEED + run)
    counts = Counter(left_gap_cells(rng, run) for _ in range(LEFT_DRAWS))
    assert_follows(counts, dict.fromkeys(PAPER_LEFT_CELLS, Fraction(1, 4)), LEFT_DRAWS)


@pytest.mark.parametrize("run", [3, 4])
def test_after_three_in_a_row_a_gap_of_one_is_never_drawn_and_the_others_have_equal_odds(run: int) -> None:
    rng = np.random.default_rng(SEED + run)
    counts = Counter(left_gap_cells(rng, run) for _ in range(LEFT_DRAWS))
    assert counts[1] == 0
    assert_follows(counts, {2: Fraction(1, 3), 3: Fraction(1, 3), 4: Fraction(1, 3)}, LEFT_DRAWS)
