"""Calibrating the fault rates against the paper's failures: only the rates change, by a rule stated here.

The paper's car failed 12 times in 525 km, median 40.6 km between failures, by cause: fake gap 6, left-lane
ghost 3, two vehicles in one cell 2, steering 1 (its Table 1). Everything but the rates is fixed and printed: the
paper model on 21 m cells, paper traffic, exact sensing (the faults are the only sensing errors, as in the paper),
the interpreter, the sensible strategy, the paper's sensor ranges, each kind's stated persistence.

1. **Lethality, one kind at a time** (``measure``): drives with that kind alone at a trial rate, restarted after
   every failure, give per kind the sweeps per km that offer it a target, the faults started and the failures
   attributed to it (``sim.faults.attribute``): a failure per fault started, ``p``. Two vehicles in one cell
   failed the paper's car; this simulator's car mostly waits in lane on them (a sensing stop, never a failure), so
   that kind counts its failures and its stops towards its share of the paper's failures.
2. **Rates** (``rates``): a target failure rate per km for the mix, ``ln 2 / 40.6 km`` (the median of exponential
   km between failures is ln 2 / rate), shared out as the paper's causes are (6, 3, 2, 1 of 12); each kind's rate
   per sweep is its share over (sweeps offering a target per km x ``p``): rare faults, each start an independent
   chance of a failure.
3. **Check** with all four kinds at once (``check``): at least 12 runs until failure, median km within a factor two
   of 40.6, and the mix over at least 30 failures, fake gaps the most common. Its figures are reported as measured.
4. **One refinement** when the mix misses (kinds interact: a ghost kills more often beside fake gaps): each kind with
   at least ``REFINE_MIN`` counted events in the check has its rate scaled by its target share over its observed
   share (``refine``); then the check again, on fresh calibration seeds.

Calibration seeds start at ``CALIBRATION_SEED`` (1001), disjoint from the evaluation's (1 .. 100). Run it:
``python -m ci.simulation.calibrate lethality`` then ``python -m ci.simulation.calibrate check --rates KIND=RATE,...``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections import Counter
from dataclasses import dataclass

import numpy as np

from ci.shared.executors import ExecutorChoice, ExecutorKind, run_jobs
from sim.parts import DriveConfig
from sim.simulator import run_drive
from sim.summary import RunSummary
from spec.faults import FaultKind, parse_faults
from spec.kinds import FailureKind

CALIBRATION_SEED = 1001
#: The paper's Table 1: failures by cause, and the median km between failures.
PAPER_CAUSES = {FaultKind.FAKE_GAP: 6, FaultKind.GHOST_LEFT: 3, FaultKind.SAME_CELL: 2, FaultKind.STEERING: 1}
PAPER_MEDIAN_KM = 40.6
FIXED = DriveConfig(km=1.0, engine="interpreter", cell_m=21.0, traffic="paper", sensor="exact", model="paper")


@dataclass(frozen=True, slots=True)
class Lethality:
    """One kind alone at a trial rate: km driven, sweeps offering a target, faults started, failures attributed."""

    kind: FaultKind
    trial_rate: float
    km: float
    offered: int
    started: int
    failures: int
    stops: int  # snapshots that could not be read, attributed to the kind (no failure: counted apart)

    @property
    def counted(self) -> int:
        """What the kind is calibrated on, what the paper counted as its failures: collisions and losses of control;
        for two vehicles in one cell also the snapshots it made unreadable (the paper's car failed on them, this
        simulator's waits in lane)."""
        return self.failures + (self.stops if self.kind is FaultKind.SAME_CELL else 0)

    @property
    def per_start(self) -> float:
        return self.counted / self.started if self.started else math.nan

    def rate_for(self, per_km: float) -> float:
        """The rate per sweep that gives ``per_km`` (counted per start x starts per km = the target)."""
        return per_km / (self.offered / self.km * self.per_start)


def _drive(seed: int, config: DriveConfig) -> RunSummary:
    return run_drive(seed, config)


def drives(config: DriveConfig, seeds: list[int], workers: int) -> list[RunSummary]:
    choice = ExecutorChoice(ExecutorKind.PROCESSES, workers) if workers > 1 else ExecutorChoice()
    return [s for _, s in sorted(run_jobs(_drive, [(seed, config) for seed in seeds], choice), key=lambda x: x[0])]


def measure(kind: FaultKind, trial_rate: float, km: float, runs: int, workers: int) -> Lethality:
    """Step 1 for one kind: ``runs`` drives of ``km`` with it alone, restarted after every failure."""
    config = DriveConfig(**{**FIXED.all_json(), "km": km, "restart_after_collision": True,
                            "faults": f"{kind.value}={trial_rate:g}"})
    seeds = list(range(CALIBRATION_SEED, CALIBRATION_SEED + runs))
    done = drives(config, seeds, workers)
    failures = sum(1 for r in done for f in r.failures if f.kind.ends_run and f.fault == kind.value)
    stops = sum(1 for r in done for f in r.stops if f.kind is FailureKind.SENSING and f.fault == kind.value)
    return Lethality(kind, trial_rate, sum(r.km for r in done), sum(r.faults[kind.value]["offered"] for r in done),
                     sum(r.faults[kind.value]["started"] for r in done), failures, stops)


def rates(measured: list[Lethality]) -> dict[FaultKind, float]:
    """Step 2: each kind's rate for its share of ln 2 / 40.6 failures per km."""
    total = sum(PAPER_CAUSES.values())
    target = math.log(2) / PAPER_MEDIAN_KM
    return {m.kind: m.rate_for(target * PAPER_CAUSES[m.kind] / total) for m in measured}


#: The fewest counted events a kind needs in a check before its rate is rescaled by it (fewer: Poisson noise).
REFINE_MIN = 5


def refine(rates_now: dict[FaultKind, float], counted: Counter[str]) -> dict[FaultKind, float]:
    """Step 4: each kind's rate times its target share over its observed share of the counted events of a check."""
    total, paper_total = sum(counted.values()), sum(PAPER_CAUSES.values())
    return {kind: rate * (PAPER_CAUSES[kind] / paper_total) / (counted[kind.value] / total)
            if counted[kind.value] >= REFINE_MIN else rate for kind, rate in rates_now.items()}


def check(faults: str, runs: int, cap_km: float, workers: int, seed: int = CALIBRATION_SEED) -> list[RunSummary]:
    """Step 3: runs until failure (capped) with every kind at its rate."""
    config = DriveConfig(**{**FIXED.all_json(), "km": cap_km, "until_failure": True, "faults": faults})
    return drives(config, list(range(seed, seed + runs)), workers)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m ci.simulation.calibrate", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="step", required=True)
    lethal = sub.add_parser("lethality", help="steps 1 and 2: each kind alone, then the rates")
    lethal.add_argument("--trial", default="fake-gap=0.05,ghost-left=0.01,same-cell=0.05,steering=0.001")
    lethal.add_argument("--km", type=float, default=10.0)
    lethal.add_argument("--runs", type=int, default=4)
    lethal.add_argument("--workers", type=int, default=2)
    verify = sub.add_parser("check", help="step 3: the rates together, runs until failure")
    verify.add_argument("--rates", required=True)
    verify.add_argument("--runs", type=int, default=12)
    verify.add_argument("--cap-km", type=float, default=200.0)
    verify.add_argument("--workers", type=int, default=2)
    verify.add_argument("--seed", type=int, default=CALIBRATION_SEED)
    args = parser.parse_args(argv)
    print(f"fixed: {FIXED.to_json()}; calibration seeds from {CALIBRATION_SEED}", flush=True)
    started = time.perf_counter()
    if args.step == "lethality":
        trial = parse_faults(args.trial, "--trial")
        measured = []
        print("| kind | trial rate | km | sweeps offering /km | started | failures | sensing stops "
              "| counted per start |")
        print("|---|---|---|---|---|---|---|---|")
        for fault in trial.faults:
            m = measure(fault.kind, fault.rate, args.km, args.runs, args.workers)
            measured.append(m)
            print(f"| {m.kind.value} | {m.trial_rate:g} | {m.km:.1f} | {m.offered / m.km:.0f} | {m.started} | "
                  f"{m.failures} | {m.stops} | {m.per_start:.4f} |", flush=True)
        if any(m.counted == 0 for m in measured):
            print("a kind caused no failure and no stop at its trial rate: raise it or the km", file=sys.stderr)
            sys.exit(1)
        derived = rates(measured)
        print("rates: " + ",".join(f"{k.value}={r:.3g}" for k, r in derived.items()))
    else:
        done = check(parse_faults(args.rates, "--rates").text(), args.runs, args.cap_km, args.workers, args.seed)
        causes = Counter(c.fault for r in done if (c := r.crash) is not None)
        stops = Counter(f.fault for r in done for f in r.stops)
        km_all = sum(r.km for r in done)
        kms = sorted(r.km for r in done)
        censored = sum(1 for r in done if r.crash is None)
        median = float(np.median(kms))
        print(f"runs {len(done)}, median km {median:.1f} (paper {PAPER_MEDIAN_KM}), censored at {args.cap_km:g} km: "
              f"{censored}; failures by fault: {dict(causes)}; km {[round(k, 1) for k in kms]}")
        print(f"in all {km_all:.1f} km, {sum(r.overtakes for r in done) / km_all:.2f} overtakes per km; stops (no "
              f"failure) by fault: {dict(stops)}")
    print(f"wall {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()
