"""The paper's experiment (Table 1 of Pagojus et al., FMAS 2021), as data to print beside ours."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class PaperRun:
    """One row of the paper's Table 1."""

    run: int
    runtime: str
    overtaken: int
    km: float
    failure: str


TABLE_1: tuple[PaperRun, ...] = (
    PaperRun(1, "5h 30m", 480, 92.8, "sensor (two vehicles at position 9)"),
    PaperRun(2, "2h 20m", 230, 43.0, "sensor (fake gap)"),
    PaperRun(3, "2h 00m", 200, 38.2, "sensor (2 vehicles at position 11)"),
    PaperRun(4, "5h 20m", 515, 102.3, "sensor (fake gap)"),
    PaperRun(5, "1h 00m", 100, 19.6, "sensor (fake gap)"),
    PaperRun(6, "2h 30m", 260, 52.5, "steering"),
    PaperRun(7, "1h 30m", 149, 28.7, "sensor (rear sensor sees an extra obstacle)"),
    PaperRun(8, "3h 10m", 296, 60.5, "sensor (fake gap)"),
    PaperRun(9, "0h 40m", 64, 12.0, "sensor (fake gap)"),
    PaperRun(10, "2h 30m", 105, 21.9, "sensor (fake gap)"),
    PaperRun(11, "4h 30m", 229, 43.8, "sensor (rear sensor sees an extra obstacle)"),
    PaperRun(12, "0h 30m", 44, 10.0, "sensor (rear sensor sees an extra obstacle)"),
)
#: The paper's medians between failures, as it reports them.
MEDIAN_KM, MEDIAN_OVERTAKEN = 40.6, 214.5
