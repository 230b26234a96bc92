"""The envelope benchmark (``ci.bench.envelope``): its seeds option, and what it reads of a drive."""

from __future__ import annotations

import pytest

from ci.bench.envelope import drive, seeds_from
from sim.parts import DriveConfig
from spec.envelope import TRACKING
from spec.errors import OptionError


def test_seeds_are_a_range_or_a_list() -> None:
    assert seeds_from("1-3") == [1, 2, 3] and seeds_from("4") == [4] and seeds_from("7,2") == [7, 2]


@pytest.mark.parametrize("text", ["", "x", "3-1", "1-", "-2", "1,,2", "0.5"])
def test_bad_seeds_name_the_option(text: str) -> None:
    with pytest.raises(OptionError, match="--seeds"):
        seeds_from(text)


def test_a_drive_reads_the_car_off_its_reference_only_under_a_sound_decision() -> None:
    """A short drive of the paper's world: every step read is one a sound decision held the AV to its envelope (none
    of the start-up's), and inside the envelope the proofs take."""
    found = drive(1, DriveConfig(0.3, model="sound", snapshots=0, opportunity_checks=0))
    assert found.traffic == "paper" and found.km >= 0.3 and found.plans > 0
    assert 0 < found.off_m.size == found.off_mps.size < found.km * 1000 / 7 * 30  # under 30 steps per metre at 7 m/s
    assert found.off_m.max() <= TRACKING.position_m and found.off_mps.max() <= TRACKING.speed_mps
    assert found.breaches == 0 and 0 < found.reference_starts <= found.plans
