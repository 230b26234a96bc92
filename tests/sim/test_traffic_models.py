"""The traffic and sensor models that do not keep to the grid: each has the stated behaviour, and seeds reproduce."""

from __future__ import annotations

import itertools
import math
import types
from collections.abc import Iterator

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sim.idm import idm_accel_mps2
from sim.parts import SENSOR_MODELS, TRAFFIC_MODELS
from sim.scene import Scene
from sim.sensors import NoisySensor, RaySensor, in_range
from sim.traffic import FollowingTraffic, PaperTraffic, SpreadTraffic, _nearest_ahead, draw_speed_mps
from sim.vehicle import Pose
from spec.lanes import Lane
from spec.physical import CAR, IDM, SPEEDS, EventSpec, NoiseSpec

SEED = 20261123
FAR_BEHIND = Pose(-10_000.0, 1.8, 0.0, 7.0)  # an AV no vehicle ever follows


@pytest.fixture
def scene() -> Iterator[Scene]:
    world = Scene()
    yield world
    world.close()


def test_an_idm_follower_alone_never_hits_its_leader_braking_to_a_standstill() -> None:
    """A leader brakes from 7 m/s to a standstill at 3 m/s^2; followers start at the equilibrium gap and at the
    minimum spawn gap, at 7 and 9.1 m/s: none touches it."""
    dt = 1 / 30
    for gap0, v0 in ((IDM.min_gap_m + 7.0 * IDM.time_gap_s, 7.0), (3.0, 7.0), (IDM.min_gap_m + 7.0, 9.1)):
        leader_x, leader_v, x, v, smallest = gap0 + CAR.length_m, 7.0, 0.0, v0, math.inf
        for _ in range(int(60 / dt)):
            leader_v = max(0.0, leader_v - 3.0 * dt)
            leader_x += leader_v * dt
            gap = leader_x - x - CAR.length_m
            v = max(0.0, v + idm_accel_mps2(v, v0, gap, v - leader_v) * dt)
            x += v * dt
            smallest = min(smallest, leader_x - x - CAR.length_m)
        assert smallest > 0.0, (gap0, v0, smallest)
        assert v < 0.05  # it stopped behind the leader


def test_an_idm_follower_settles_at_its_leaders_speed_and_gap() -> None:
    dt, leader_v, x, v = 1 / 30, 6.4, 0.0, 7.5
    leader_x = 60.0
    for _ in range(int(300 / dt)):
        leader_x += leader_v * dt
        v = max(0.0, v + idm_accel_mps2(v, 7.5, leader_x - x - CAR.length_m, v - leader_v) * dt)
        x += v * dt
    assert v == pytest.approx(leader_v, abs=0.01)
    assert leader_x - x - CAR.length_m >= IDM.min_gap_m + leader_v * IDM.time_gap_s  # at least s0 + v T


def test_speeds_have_the_stated_distribution() -> None:
    rng = np.random.default_rng(SEED)
    speeds = np.array([draw_speed_mps(rng) for _ in range(20000)])
    assert speeds.mean() == pytest.approx(SPEEDS.mean_mps, abs=0.02)
    assert speeds.std() == pytest.approx(SPEEDS.sd_mps, rel=0.03)
    cut = SPEEDS.cut_sd * SPEEDS.sd_mps
    assert speeds.min() >= SPEEDS.mean_mps - cut and speeds.max() <= SPEEDS.mean_mps + cut


def positions(model: type[PaperTraffic], seed: int, seconds: float, scene: Scene, **kw: object) -> list[float]:
    traffic = model(scene, np.random.default_rng(seed), 0.0, **kw)  # type: ignore[arg-type]
    for _ in range(int(seconds * 30)):
        traffic.advance(1 / 30, FAR_BEHIND)
    return [round(car.x_m, 6) for car in traffic.cars()]


@pytest.mark.parametrize("model", [SpreadTraffic, FollowingTraffic])
def test_seeds_reproduce_and_differ(model: type[PaperTraffic], scene: Scene) -> None:
    assert positions(model, 5, 20, scene) == positions(model, 5, 20, scene)
    assert positions(model, 5, 20, scene) != positions(model, 6, 20, scene)


def test_following_traffic_compresses_platoons_below_the_common_speed_without_touching(scene: Scene) -> None:
    traffic = FollowingTraffic(scene, np.random.default_rng(SEED), 0.0, events=EventSpec(stop_rate_per_h=0.0))
    for _ in range(120 * 30):
        traffic.advance(1 / 30, FAR_BEHIND)
    speeds = [traffic.drivers[car.body].speed_mps for car in traffic.left]
    desired = [traffic.drivers[car.body].desired_mps for car in traffic.left]
    assert traffic.collisions == 0
    assert any(s < d - 0.2 for s, d in zip(speeds, desired))  # someone is held up by a slower leader
    ordered = sorted(traffic.left, key=lambda c: c.x_m)
    assert all(b.x_m - a.x_m - CAR.length_m > 0 for a, b in itertools.pairwise(ordered))


def test_spawn_gaps_are_continuous_and_never_below_the_stated_minimum(scene: Scene) -> None:
    gaps = []
    for seed in range(40):
        traffic = SpreadTraffic(scene, np.random.default_rng(seed), 0.0)
        xs = sorted(car.x_m for car in traffic.left)
        gaps += [b - a - CAR.length_m for a, b in itertools.pairwise(xs)]
    assert min(gaps) >= EventSpec().min_spawn_gap_m - 1e-9
    assert min(gaps) < 5.0 and len({round(g, 3) for g in gaps}) > len(gaps) // 2  # not whole cells any more


def test_stops_happen_at_the_stated_rate(scene: Scene) -> None:
    rate = 60.0  # per vehicle-hour, high enough to count in 10 simulated minutes
    traffic = FollowingTraffic(scene, np.random.default_rng(SEED), 0.0, events=EventSpec(stop_rate_per_h=rate))
    stops, was = 0, {car.body: False for car in traffic.left}
    for _ in range(600 * 30):
        traffic.advance(1 / 30, FAR_BEHIND)
        for car in traffic.left:
            now = traffic.drivers[car.body].stopping_until_s >= traffic.t_s
            stops += now and not was[car.body]
            was[car.body] = now
    expected = rate * len(traffic.left) * 600 / 3600  # minus the time each spends stopped: a little fewer
    assert 0.6 * expected <= stops <= 1.1 * expected


def test_the_noisy_sensor_misses_and_blurs_at_the_stated_rates(scene: Scene) -> None:
    from sim.vehicle import KinematicCar

    cars = [KinematicCar(scene, 20.0 + 25 * k, scene.lane_y(Lane.LEFT), 7.0) for k in range(1)]
    truth = in_range(0.0, scene.lane_y(Lane.LEFT), cars, [])
    noise = NoiseSpec(range_sd_m=0.5, miss_rate=0.1)
    sensor = NoisySensor(scene, np.random.default_rng(SEED), noise=noise)
    reads = [sensor.read(truth) for _ in range(4000)]
    seen = [r[0].dx_m - truth.readings[0].dx_m for r in reads if r]
    assert 1 - len(seen) / len(reads) == pytest.approx(noise.miss_rate, abs=0.02)
    assert np.std(seen) == pytest.approx(noise.range_sd_m, rel=0.08) and abs(np.mean(seen)) < 0.05
    exact = RaySensor(scene, np.random.default_rng(SEED)).read(truth)
    assert exact == truth.readings


def test_the_registries_name_every_model() -> None:
    assert set(TRAFFIC_MODELS) == {"paper", "spread", "following"}
    assert set(SENSOR_MODELS) == {"exact", "noisy"}


def test_the_av_is_a_leader_in_the_left_lane_and_touching_it_is_not_a_traffic_collision(scene: Scene) -> None:
    traffic = FollowingTraffic(scene, np.random.default_rng(SEED), 0.0, events=EventSpec(stop_rate_per_h=0.0))
    last = min(traffic.left, key=lambda c: c.x_m)
    av = Pose(last.x_m + CAR.length_m + 6.0, 1.8, 0.0, 0.0)  # standing 6 m ahead of the last car
    for _ in range(20 * 30):
        traffic.advance(1 / 30, av)
    assert traffic.drivers[last.body].speed_mps < 0.05 and av.x_m - last.x_m - CAR.length_m > 0
    assert traffic.collisions == 0


def test_a_vehicle_behind_the_av_follows_its_speed_along_the_road_not_along_its_heading(scene: Scene) -> None:
    traffic = SpreadTraffic(scene, np.random.default_rng(SEED), 0.0, events=EventSpec(stop_rate_per_h=0.0))
    last = min(traffic.left, key=lambda c: c.x_m)
    driver = traffic.drivers[last.body]
    av = Pose(last.x_m + CAR.length_m + IDM.min_gap_m / 2, 1.8, 0.6, driver.speed_mps + 1.0)  # closed up, turning
    assert av.along_mps < driver.speed_mps < av.speed_mps
    traffic.advance(1 / 30, av)
    assert driver.speed_mps == av.along_mps


def test_two_vehicles_that_touch_are_one_traffic_collision_and_both_stop(scene: Scene) -> None:
    traffic = SpreadTraffic(scene, np.random.default_rng(SEED), 0.0, events=EventSpec(stop_rate_per_h=0.0))
    front, behind = sorted(traffic.left, key=lambda c: -c.x_m)[:2]
    behind.place(front.x_m - 2.0)  # overlapping
    traffic.advance(1 / 30, FAR_BEHIND)
    assert traffic.collisions == 1
    assert traffic.drivers[front.body].wrecked and traffic.drivers[behind.body].wrecked
    traffic.advance(1 / 30, FAR_BEHIND)
    assert traffic.collisions == 1 and traffic.drivers[behind.body].speed_mps == 0.0


@given(st.lists(st.sampled_from([-30.0, -12.5, 0.0, 0.0, 4.0, 17.25, 40.0]) | st.floats(-100, 100), max_size=8),
       st.floats(-100, 100), st.sampled_from([1.0, -1.0]), st.booleans())
def test_the_leader_found_from_the_end_is_the_nearest_vehicle_ahead_and_the_first_of_equals(
        xs: list[float], x_m: float, sign: float, front_first: bool) -> None:
    cars = [types.SimpleNamespace(x_m=x) for x in xs]
    if front_first:  # as a step moves them: then the search from the end is taken
        cars.sort(key=lambda c: -sign * c.x_m)
    ordered = all(sign * (a.x_m - b.x_m) >= 0 for a, b in itertools.pairwise(cars))
    ahead = [c for c in cars if sign * (c.x_m - x_m) > 0]
    plain = min(ahead, key=lambda c: sign * (c.x_m - x_m)) if ahead else None
    assert _nearest_ahead(cars, ordered, x_m, sign) is plain  # type: ignore[arg-type]
