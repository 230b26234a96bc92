"""The world: one PyBullet client in DIRECT mode, gravity, and a flat road surface.

Coordinates: x along the road in the AV's direction of travel, y to the AV's left; the
AV's (left) lane is centred at y = +lane_width/2, the oncoming (right) lane at -lane_width/2.
Each Simulator owns one Scene, so simulators never share a physics world.
"""

from __future__ import annotations

import contextlib
import functools
import os
import sys
from collections.abc import Iterator

from sim.driver.control import lane_y
from spec.physical import LOOP


@contextlib.contextmanager
def _quiet(fd: int) -> Iterator[None]:
    """Silence a file descriptor (1 or 2: C-level prints) for the duration, keeping Python's streams intact."""
    (sys.stdout if fd == 1 else sys.stderr).flush()
    saved = os.dup(fd)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), fd)
        yield
    finally:
        os.dup2(saved, fd)
        os.close(saved)


with _quiet(2):  # PyBullet's C code prints its build time on stderr when it loads
    import pybullet as p
    from pybullet_utils import bullet_client


class Scene:
    """A private physics world with a road."""

    def __init__(self, dt_s: float = LOOP.physics_dt_s) -> None:
        with _quiet(1):  # PyBullet's C code prints "argv[0]=" when it connects
            self.client = bullet_client.BulletClient(connection_mode=p.DIRECT)
        self.dt_s = dt_s
        self.client.setGravity(0, 0, -9.81)
        self.client.setTimeStep(dt_s)
        ground = self.client.createCollisionShape(p.GEOM_PLANE)
        self.ground = self.client.createMultiBody(0, ground)
        self.client.changeDynamics(self.ground, -1, lateralFriction=1.0, restitution=0.0)
        # the calls made on every physics step, bound once: BulletClient looks each call up by name otherwise
        own = {"physicsClientId": self.client._client}
        self._step = functools.partial(p.stepSimulation, **own)
        self._reset_pose = functools.partial(p.resetBasePositionAndOrientation, **own)
        self._contacts = functools.partial(p.getContactPoints, **own)

    lane_y = staticmethod(lane_y)  # the y of a lane's centre line (``sim.driver.control.lane_y``)

    def step(self) -> None:
        """One physics step of ``dt_s``."""
        self._step()

    def place(self, body: int, xyz: tuple[float, float, float]) -> None:
        """Put a body at ``xyz``, unrotated (kinematic traffic)."""
        self._reset_pose(body, xyz, (0, 0, 0, 1))

    def touching(self, body: int) -> set[int]:
        """The bodies in contact with ``body`` after the last step."""
        return {point[2] for point in self._contacts(bodyA=body)}

    def close(self) -> None:
        """Release the physics world."""
        self.client.disconnect()
