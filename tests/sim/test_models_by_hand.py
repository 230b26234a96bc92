"""Every registered traffic and sensor model on constructed inputs whose answers are worked out by hand: one step of
each traffic model with the vehicles placed and their drivers set by the test, and each sensor on vehicles placed
where what it must report is known. The cases are keyed by the registries' names, so a model registered without
its direct test fails ``test_every_registered_*_model_has_a_direct_test``.

The noisy sensor's rates are checked over 100,000 readings (fixed seed) against exact acceptance intervals at a
false-alarm probability of 1e-6 each (binomial for the misses, chi-square for the variance, normal for the mean):
a correct sensor fails that test with probability at most 3e-6 (a union bound)."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.stats import binom, chi2, norm

from sim.driver.discretiser import reading_cell
from sim.driver.readings import Reading
from sim.parts import SENSOR_MODELS, TRAFFIC_MODELS
from sim.scene import Scene
from sim.sensors import Truth, in_range
from sim.traffic import Driver, PaperTraffic, SpreadTraffic, draw_speed_mps
from sim.vehicle import KinematicCar, Pose
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.physical import SENSORS, EventSpec, NoiseSpec, SpeedSpec

SEED = 20261125
CELL_M, COMMON_MPS, LENGTH_M = 21.0, 7.0, 4.5  # the paper's cell and common speed; a car's length
S0_M = 2.0  # the minimum gap (IDM's s0): a spread vehicle this close to its leader takes the leader's speed
IDM_T_S, IDM_A_MPS2, IDM_B_MPS2 = 1.6, 0.73, 1.67  # Table I of Treiber, Hennecke and Helbing (2000)
DT_S = 1 / 30
AV_IN_RIGHT_LANE = Pose(-10_000.0, -1.8, 0.0, 7.0)  # leads no left-lane vehicle; oncoming ones never follow it
NO_STOPS = EventSpec(stop_rate_per_h=0.0)
FALSE_ALARM = 1e-6


@pytest.fixture(scope="module")
def scene() -> Iterator[Scene]:
    world = Scene()
    yield world
    world.close()


def staged(traffic: SpreadTraffic, left: list[tuple[float, float, float]],
           oncoming: list[tuple[float, float, float]]) -> None:
    """Put each vehicle at x_m with its (desired, current) speed: (x_m, desired_mps, speed_mps) per vehicle."""
    for car, (x_m, desired_mps, speed_mps) in zip(traffic.left + traffic.oncoming, left + oncoming, strict=True):
        car.place(x_m)
        traffic.drivers[car.body] = Driver(desired_mps, speed_mps)


def idm_by_hand_mps2(v: float, v0: float, s: float, dv: float) -> float:
    desired_gap_m = S0_M + max(0.0, v * IDM_T_S + v * dv / (2 * math.sqrt(IDM_A_MPS2 * IDM_B_MPS2)))
    return IDM_A_MPS2 * (1 - (v / v0) ** 4 - (desired_gap_m / s) ** 2)


# -- traffic models ------------------------------------------------------------------------------------------------
def paper_case(factory: Callable[..., PaperTraffic], scene: Scene) -> None:
    """Whole cells apart at the common speed; one step moves every vehicle exactly 7 m/s times the step; a vehicle
    more than 5 cells behind the AV is respawned a paper gap ahead, one exactly 5 cells behind is not."""
    traffic = factory(scene, np.random.default_rng(SEED), 0.0)
    left_x = [car.x_m for car in traffic.left]
    oncoming_x = [car.x_m for car in traffic.oncoming]
    assert left_x[0] == 2 * CELL_M
    assert {round(b - a, 9) for a, b in itertools.pairwise(left_x)} <= {CELL_M * g for g in (1, 2, 3, 4)}
    oncoming_gaps = {round(b - a, 9) for a, b in zip([0.0, *oncoming_x], oncoming_x)}
    assert oncoming_gaps <= {CELL_M * g for g in (8, 12, 16, 20)}
    assert [car.velocity_mps for car in traffic.cars()] == [COMMON_MPS] * 6 + [-COMMON_MPS] * 3
    traffic.advance(0.5, AV_IN_RIGHT_LANE)
    assert [car.x_m for car in traffic.left] == pytest.approx([x + 3.5 for x in left_x], abs=1e-9)
    assert [car.x_m for car in traffic.oncoming] == pytest.approx([x - 3.5 for x in oncoming_x], abs=1e-9)
    stays, goes, far_oncoming = traffic.left[0], traffic.left[1], traffic.oncoming[0]
    stays.place(-5 * CELL_M)
    goes.place(-5 * CELL_M - 0.5)
    far_oncoming.place(-5 * CELL_M - 0.5)
    front = max(car.x_m for car in traffic.left)
    last = max(car.x_m for car in traffic.oncoming)
    assert traffic.respawn_behind(0.0) == 2
    assert stays.x_m == -5 * CELL_M and stays.respawns == 0
    assert round(goes.x_m - front, 9) in {CELL_M * g for g in (1, 2, 3, 4)} and goes.respawns == 1
    assert round(far_oncoming.x_m - last, 9) in {CELL_M * g for g in (8, 12, 16, 20)}
    assert far_oncoming.respawns == 1 and far_oncoming.velocity_mps == -COMMON_MPS


def spread_case(factory: Callable[..., SpreadTraffic], scene: Scene) -> None:
    """One step of 1/30 s: a free vehicle drives at its own desired speed at once; one that is (after its leader's
    move) within 2 m of a slower leader takes the leader's speed; one held up before, now 2.7 m behind, drives at
    its own speed again; an oncoming vehicle drives at its own speed towards the AV."""
    traffic = factory(scene, np.random.default_rng(SEED), 0.0, events=NO_STOPS)
    staged(traffic, [(0.0, 7.5, 5.0),  # free, 1994 m behind the next one
                     (1994.0, 7.0, 7.0), (2000.0, 6.0, 6.0),  # 1.5 m behind a 6 m/s leader: 1.7 m after its move
                     (3000.0, 7.0, 6.0), (3007.0, 6.0, 6.0),  # held up earlier, 2.5 m gap, 2.7 m after the move
                     (9000.0, 8.0, 8.0)],
           [(500.0, 6.5, 6.5), (9000.0, 7.0, 7.0), (9500.0, 7.0, 7.0)])
    traffic.advance(DT_S, AV_IN_RIGHT_LANE)
    speeds = [traffic.drivers[car.body].speed_mps for car in traffic.cars()]
    assert speeds == [7.5, 6.0, 6.0, 7.0, 6.0, 8.0, 6.5, 7.0, 7.0]
    assert [car.velocity_mps for car in traffic.cars()] == [7.5, 6.0, 6.0, 7.0, 6.0, 8.0, -6.5, -7.0, -7.0]
    assert traffic.left[1].x_m == pytest.approx(1994.0 + 6.0 * DT_S, abs=1e-9)
    assert traffic.oncoming[0].x_m == pytest.approx(500.0 - 6.5 * DT_S, abs=1e-9)
    assert traffic.collisions == 0


def following_case(factory: Callable[..., SpreadTraffic], scene: Scene) -> None:
    """One step of 1/30 s of an IDM follower 25.5 m behind a 6 m/s leader that is at its desired speed with no one
    ahead (so it keeps 6 m/s), closing at 1 m/s; then, the AV in the left lane at 5 m/s 25.5 m ahead of a follower,
    closing at 2 m/s (the AV is a leader too): each new speed worked out from the published equations."""
    traffic = factory(scene, np.random.default_rng(SEED), 0.0, events=NO_STOPS)
    far_behind = [(-9000.0, 7.0, 7.0), (-9500.0, 7.0, 7.0), (-9900.0, 7.0, 7.0)]
    oncoming = [(500.0, 7.0, 7.0), (9000.0, 7.0, 7.0), (9500.0, 7.0, 7.0)]
    staged(traffic, [(-8000.0, 7.0, 7.0), (8970.0, 7.5, 7.0), (9000.0, 6.0, 6.0), *far_behind], oncoming)
    traffic.advance(DT_S, AV_IN_RIGHT_LANE)
    leader, follower = traffic.left[2], traffic.left[1]
    leader_x = 9000.0 + 6.0 * DT_S  # a (1 - (6 / 6)^4) = 0 on a free road: it keeps 6 m/s
    behind_car = 7.0 + idm_by_hand_mps2(7.0, 7.5, leader_x - 8970.0 - LENGTH_M, 1.0) * DT_S
    assert traffic.drivers[leader.body].speed_mps == 6.0 and leader.x_m == leader_x
    assert traffic.drivers[follower.body].speed_mps == pytest.approx(behind_car, abs=1e-12)
    assert follower.x_m == pytest.approx(8970.0 + behind_car * DT_S, abs=1e-9)

    staged(traffic, [(-8000.0, 7.0, 7.0), (2970.0, 7.5, 7.0), (-8500.0, 6.0, 6.0), *far_behind], oncoming)
    traffic.advance(DT_S, Pose(3000.0, 1.8, 0.0, 5.0))  # the AV does not move in the traffic's step
    behind_av = 7.0 + idm_by_hand_mps2(7.0, 7.5, 3000.0 - 2970.0 - LENGTH_M, 2.0) * DT_S
    assert traffic.drivers[follower.body].speed_mps == pytest.approx(behind_av, abs=1e-12)
    assert behind_av < behind_car < 7.0  # both brake, behind the slower AV harder
    assert traffic.collisions == 0


TRAFFIC_CASES: dict[str, Callable[..., None]] = {"paper": paper_case, "spread": spread_case,
                                                 "following": following_case}


def test_every_registered_traffic_model_has_a_direct_test() -> None:
    assert set(TRAFFIC_CASES) == set(TRAFFIC_MODELS)


@pytest.mark.parametrize("name", sorted(TRAFFIC_MODELS))
def test_each_registered_traffic_model_moves_and_respawns_its_vehicles_as_worked_out_by_hand(
        name: str, scene: Scene) -> None:
    TRAFFIC_CASES[name](TRAFFIC_MODELS[name], scene)


@pytest.mark.parametrize("name", sorted(TRAFFIC_MODELS))
@pytest.mark.parametrize("front_m", [-40.0, 0.0, LENGTH_M - 0.01])
def test_a_vehicle_respawned_when_none_is_wholly_ahead_of_the_av_enters_beyond_its_left_range(
        name: str, front_m: float, scene: Scene) -> None:
    """The paper's rule places a respawned left-lane vehicle a gap ahead of the front-most one; when that one is
    beside or behind the AV (the AV leads the lane), the gap is counted from the end of the AV's left sensor's range
    instead, so the vehicle never appears beside, inside or just ahead of the AV (in spread traffic, seed 3 at 21 m
    once put one 1.6 m ahead of the AV's centre). With a vehicle wholly ahead of the AV, the paper's rule stands."""
    av_x_m, range_m = 1000.0, SENSORS.left_range_m
    for ahead_m, base_m in ((front_m, av_x_m + range_m), (LENGTH_M + 0.01, av_x_m + LENGTH_M + 0.01)):
        traffic = TRAFFIC_MODELS[name](scene, np.random.default_rng(SEED), 0.0)
        goes, front, *rest = traffic.left
        for i, car in enumerate(rest):
            car.place(av_x_m - 60.0 - i)  # behind the AV, not far enough to be removed
        for i, car in enumerate(traffic.oncoming):
            car.place(av_x_m + 2000.0 + 200.0 * i)  # far ahead: none respawns
        front.place(av_x_m + ahead_m)
        goes.place(av_x_m - 5 * CELL_M - 0.5)
        assert traffic.respawn_behind(av_x_m) == 1 and goes.respawns == 1
        gap_m = goes.x_m - base_m
        if name == "paper":
            assert round(gap_m, 9) in {CELL_M * g for g in (1, 2, 3, 4)}, (ahead_m, gap_m)
        else:
            assert LENGTH_M <= gap_m <= 5 * CELL_M, (ahead_m, gap_m)


def test_a_drawn_speed_is_the_normal_draw_cut_at_three_sd() -> None:
    """7 m/s, sd 0.7 m/s, cut at 3 sd: 4.9 to 9.1 m/s; the generator is asked for exactly that normal (a stand-in
    generator returns the draws scripted here)."""
    speeds = SpeedSpec()
    assert (speeds.mean_mps, speeds.sd_mps, speeds.cut_sd) == pytest.approx((7.0, 0.7, 3.0), abs=1e-12)
    scripted, asked = iter([7.3, 100.0, -100.0, 9.09, 4.91]), []

    def normal(mean: float, sd: float) -> float:
        asked.append((mean, sd))
        return next(scripted)

    for kept in (7.3, 9.1, 4.9, 9.09, 4.91):
        assert draw_speed_mps(SimpleNamespace(normal=normal)) == pytest.approx(kept, abs=1e-12)  # type: ignore[arg-type]
    assert len(asked) == 5 and all(mean == 7.0 and sd == pytest.approx(0.7, abs=1e-12) for mean, sd in asked)


def test_the_initial_left_lane_never_has_four_vehicles_in_consecutive_cells(scene: Scene) -> None:
    """The paper's rule holds from the first placement, and the count of vehicles in a row at the front that the
    respawns go on from is the true one (seeds 34, 233 and 291 once placed four in a row)."""
    for seed in range(300):
        traffic = PaperTraffic(scene, np.random.default_rng(seed), 0.0)
        cells = [round(car.x_m / CELL_M) for car in traffic.left]
        run = longest = 1
        for a, b in itertools.pairwise(cells):
            run = run + 1 if b - a == 1 else 1
            longest = max(longest, run)
        assert longest <= 3, (seed, cells)
        assert traffic.run == run, (seed, cells, traffic.run)
        for car in traffic.cars():
            scene.client.removeBody(car.body)


# -- sensor models -------------------------------------------------------------------------------------------------
def _placed(scene: Scene) -> tuple[list[KinematicCar], list[KinematicCar], Truth]:
    """The AV at x = 0 in the left lane: left-lane vehicles 30 m ahead, 60 m ahead (behind the first) and 40 m
    behind; oncoming ones 41 m, 60 m (behind the first, seen from the AV's front-right corner), 100 m (beside both)
    and 400 m ahead (out of range)."""
    left = [KinematicCar(scene, x, scene.lane_y(Lane.LEFT), 7.0) for x in (30.0, 60.0, -40.0)]
    oncoming = [KinematicCar(scene, x, scene.lane_y(Lane.RIGHT), -7.0) for x in (41.0, 60.0, 100.0, 400.0)]
    return left, oncoming, in_range(0.0, scene.lane_y(Lane.LEFT), left, oncoming)


def _removed(scene: Scene, cars: list[KinematicCar]) -> None:
    for car in cars:
        scene.client.removeBody(car.body)


def exact_case(factory: Callable[..., object], scene: Scene) -> None:
    """The exact sensor reports each vehicle its ray reaches first, at its true distance, so the cells are the stated
    rule's: 30 m ahead is one cell ahead (rounded), 40 m behind two cells behind, an oncoming vehicle 41 m ahead one
    cell (rounded towards the AV), one 100 m ahead four cells; the vehicles hidden behind another are not seen."""
    left, oncoming, truth = _placed(scene)
    try:
        seen = factory(scene, np.random.default_rng(SEED)).read(truth)  # type: ignore[attr-defined]
        assert [(r.lane, r.body, r.dx_m) for r in seen] == [
            (Lane.LEFT, left[0].body, 30.0), (Lane.LEFT, left[2].body, -40.0), (Lane.RIGHT, oncoming[0].body, 41.0),
            (Lane.RIGHT, oncoming[2].body, 100.0)]
        av = PAPER_GRID.av_cell
        assert [reading_cell(r, Lane.LEFT, PAPER_GRID) for r in seen] == [av + 1, av - 2, av + 1, av + 4]
    finally:
        _removed(scene, left + oncoming)


def noisy_case(factory: Callable[..., object], scene: Scene) -> None:
    """With no noise and no misses the noisy sensor is the exact one; with every reading missed it sees nothing;
    otherwise it sees only what the exact one sees, each at most a few sd off (rates: the statistical test)."""
    left, oncoming, truth = _placed(scene)
    try:
        exact = SENSOR_MODELS["exact"](scene, np.random.default_rng(SEED)).read(truth)
        perfect = factory(scene, np.random.default_rng(SEED), noise=NoiseSpec(range_sd_m=0.0, miss_rate=0.0))
        blind = factory(scene, np.random.default_rng(SEED), noise=NoiseSpec(range_sd_m=0.5, miss_rate=1.0))
        noisy = factory(scene, np.random.default_rng(SEED), noise=NoiseSpec(range_sd_m=0.5, miss_rate=0.0))
        assert perfect.read(truth) == exact and blind.read(truth) == ()  # type: ignore[attr-defined]
        blurred = noisy.read(truth)  # type: ignore[attr-defined]
        assert [(r.lane, r.body) for r in blurred] == [(r.lane, r.body) for r in exact]
        assert all(0 < abs(b.dx_m - r.dx_m) < 6 * 0.5 for b, r in zip(blurred, exact))
    finally:
        _removed(scene, left + oncoming)


SENSOR_CASES: dict[str, Callable[..., None]] = {"exact": exact_case, "noisy": noisy_case}


def test_every_registered_sensor_model_has_a_direct_test() -> None:
    assert set(SENSOR_CASES) == set(SENSOR_MODELS)


@pytest.mark.parametrize("name", sorted(SENSOR_MODELS))
def test_each_registered_sensor_model_reports_what_is_worked_out_by_hand(name: str, scene: Scene) -> None:
    SENSOR_CASES[name](SENSOR_MODELS[name], scene)


def test_the_noisy_sensor_misses_and_blurs_at_the_stated_rates() -> None:
    """1,000 reads of 100 vehicles that every ray reaches (a stand-in for PyBullet's ray test): the misses are
    binomial(100,000, 0.01), the errors normal with mean 0 and sd 0.5 m, each checked at 1e-6."""
    noise = NoiseSpec()
    assert (noise.range_sd_m, noise.miss_rate) == (0.5, 0.01)
    vehicles, reads = 100, 1000
    truth = Truth(tuple(Reading(Lane.LEFT, body, 10.0 + body) for body in range(vehicles)),
                  tuple((10.0 + body, 1.8) for body in range(vehicles)), 0.0, 1.8)
    every_ray_hits = SimpleNamespace(client=SimpleNamespace(
        rayTestBatch=lambda starts, ends: [(body,) for body in range(len(ends))]))
    sensor = SENSOR_MODELS["noisy"](every_ray_hits, np.random.default_rng(SEED))  # type: ignore[arg-type]
    errors: list[float] = []
    for _ in range(reads):
        errors += [r.dx_m - (10.0 + r.body) for r in sensor.read(truth)]
    n = vehicles * reads
    low, high = binom.interval(1 - FALSE_ALARM, n, 0.01)
    assert low <= n - len(errors) <= high, (n - len(errors)) / n
    sample = np.array(errors)
    var_low, var_high = chi2.interval(1 - FALSE_ALARM, len(sample) - 1)
    scaled = (len(sample) - 1) * sample.var(ddof=1) / 0.5**2
    assert var_low <= scaled <= var_high, sample.std(ddof=1)
    assert abs(sample.mean()) <= norm.isf(FALSE_ALARM / 2) * 0.5 / math.sqrt(len(sample)), sample.mean()
