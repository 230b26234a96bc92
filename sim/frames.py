"""The seconds before an event, seen by PyBullet's own camera: the drive replayed from its seed and configuration
(drives are deterministic: one seeded generator per part) up to the event, and frames rendered headless (TinyRenderer)
with the AV, the same-direction and the oncoming vehicles coloured and the lane lines drawn."""

from __future__ import annotations

import contextlib
from dataclasses import dataclass

import numpy as np
import pybullet as p

from sim.parts import DriveConfig
from sim.scene import Scene
from sim.simulator import Simulator, assemble
from spec.physical import ROAD

#: Colours (RGBA) of the AV, same-direction vehicles and oncoming vehicles, and of the lane lines.
AV_RGBA, SAME_RGBA, ONCOMING_RGBA = (0.1, 0.7, 0.3, 1.0), (0.17, 0.48, 0.81, 1.0), (0.9, 0.1, 0.11, 1.0)
ROAD_RGBA, LINE_RGBA = (0.35, 0.35, 0.38, 1.0), (1.0, 1.0, 1.0, 1.0)
WIDTH_PX, HEIGHT_PX = 480, 240
LINE_LENGTH_M, LINE_WIDTH_M = 400.0, 0.15


class _Reached(Exception):
    """The replay has rendered its last frame."""


#: How long the replay goes on after the event, for the event's record (made when it ends) to be there.
AFTER_S = 1.0


@dataclass(frozen=True, slots=True)
class Frame:
    """One rendered instant: the drive's clock and the image (height x width x RGB)."""

    t_s: float
    image: np.ndarray


@dataclass(frozen=True, slots=True)
class Replay:
    """The frames of a replay, and whether it met the event again (a drive replays exactly from its seed with the
    code that drove it; with other code it may not)."""

    frames: list[Frame]
    met: bool


def replay_frames(seed: int, config: DriveConfig, event_t_s: float, kind: str, count: int = 4,
                  before_s: float = 3.0) -> Replay:
    """``count`` frames evenly from ``before_s`` before ``event_t_s`` (the drive's clock) to it, from the drive of
    ``seed`` under ``config`` replayed headless, and whether the replay recorded an encounter of ``kind``
    ("contact", "near_miss") at that time; fewer frames when the replay ends before."""
    times = [max(0.0, event_t_s - before_s + i * before_s / max(1, count - 1)) for i in range(count)]
    stop_s = event_t_s + AFTER_S
    sim = assemble(seed, config)
    frames: list[Frame] = []
    tick = sim._tick
    lines: dict[Scene, list[int]] = {}  # per scene (a collision restarts the drive in a fresh one): its road bodies

    def watched(dt_s: float) -> bool:
        going = tick(dt_s)
        while len(frames) < len(times) and sim.summary.sim_time_s >= times[len(frames)] - 1e-9:
            frames.append(Frame(round(sim.summary.sim_time_s, 2), _render(sim, lines)))
        if sim.summary.sim_time_s >= stop_s:
            raise _Reached
        return going

    sim._tick = watched  # type: ignore[method-assign]
    try:
        with contextlib.suppress(_Reached):
            sim.drive(config.km, config.stops_at_failure, config.until_sensing_failure)
        met = any(e.kind == kind and abs(e.t_s - event_t_s) < 0.05 for e in sim.summary.safety.encounters)
    finally:
        sim.close()
    return Replay(frames, met)


def _render(sim: Simulator, drawn: dict[Scene, list[int]]) -> np.ndarray:
    """The scene from above and behind the AV, vehicles coloured."""
    scene: Scene = sim.scene
    client = scene.client
    pose = sim.car.pose()
    lines = drawn.setdefault(scene, [])
    if not lines:  # visual-only bodies (no collision shape): nothing the drive could touch
        road = client.createVisualShape(p.GEOM_BOX, halfExtents=(LINE_LENGTH_M / 2, ROAD.lane_width_m, 0.005),
                                        rgbaColor=ROAD_RGBA)
        lines.append(client.createMultiBody(0, -1, road, basePosition=(pose.x_m, 0.0, 0.005)))
        for y in (-ROAD.lane_width_m, 0.0, ROAD.lane_width_m):
            shape = client.createVisualShape(p.GEOM_BOX, halfExtents=(LINE_LENGTH_M / 2, LINE_WIDTH_M / 2, 0.005),
                                             rgbaColor=LINE_RGBA)
            lines.append(client.createMultiBody(0, -1, shape, basePosition=(pose.x_m, y, 0.015)))
    for body in lines:
        (_, y, z), _ = client.getBasePositionAndOrientation(body)
        client.resetBasePositionAndOrientation(body, (pose.x_m, y, z), (0, 0, 0, 1))
    client.changeVisualShape(sim.car.body, -1, rgbaColor=AV_RGBA)
    for car in sim.traffic.left:
        client.changeVisualShape(car.body, -1, rgbaColor=SAME_RGBA)
    for car in sim.traffic.oncoming:
        client.changeVisualShape(car.body, -1, rgbaColor=ONCOMING_RGBA)
    eye = (pose.x_m - 12.0, pose.y_m - 5.0, 7.0)
    target = (pose.x_m + 20.0, 0.0, 0.0)
    view = client.computeViewMatrix(eye, target, (0, 0, 1))
    projection = client.computeProjectionMatrixFOV(50.0, WIDTH_PX / HEIGHT_PX, 0.5, 300.0)
    _, _, rgba, _, _ = client.getCameraImage(WIDTH_PX, HEIGHT_PX, view, projection, renderer=p.ER_TINY_RENDERER)
    image = np.reshape(np.asarray(rgba, dtype=np.uint8), (HEIGHT_PX, WIDTH_PX, 4))[:, :, :3]
    return image

