"""Vehicles: the AV, a wheeled multibody driven through its wheel motors, and kinematic traffic cars.

The AV is never teleported or given a velocity: a speed command sets the target angular
velocity of the four wheel motors, ramped at no more than the acceleration or braking
limit, and a steering command sets the front hinges' target angle.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable
from dataclasses import dataclass

from sim.scene import Scene, p
from spec.physical import CAR, CarSpec

_WHEEL_AXIS_ROT = p.getQuaternionFromEuler((math.pi / 2, 0, 0))  # cylinder's axis from z to y


@dataclass(frozen=True, slots=True)
class Pose:
    """Where a vehicle is and how it moves, in the scene's coordinates."""

    x_m: float
    y_m: float
    yaw_rad: float
    speed_mps: float  # along the vehicle's heading

    @property
    def along_mps(self) -> float:
        """Its speed along the road (the scene's x): what the model's speeds and gaps are measured along, less than
        ``speed_mps`` by the cosine of the heading while the car moves sideways."""
        return self.speed_mps * math.cos(self.yaw_rad)


class WheeledCar:
    """The AV: chassis, two steering hinges, four wheels; velocity-controlled wheel motors."""

    def __init__(self, scene: Scene, x_m: float, y_m: float, spec: CarSpec = CAR) -> None:
        self.scene, self.spec, c = scene, spec, scene.client
        chassis_half = (spec.length_m / 2, spec.width_m / 2, spec.height_m / 4)
        chassis = c.createCollisionShape(p.GEOM_BOX, halfExtents=chassis_half)
        wheel = c.createCollisionShape(p.GEOM_CYLINDER, radius=spec.wheel_radius_m, height=spec.wheel_width_m,
                                       collisionFrameOrientation=_WHEEL_AXIS_ROT)
        lift = spec.height_m / 4 + 0.15  # chassis centre above the axles
        front, rear, side = spec.wheelbase_m / 2, -spec.wheelbase_m / 2, spec.track_m / 2
        # links: 0 steer FL, 1 wheel FL, 2 steer FR, 3 wheel FR, 4 wheel RL, 5 wheel RR
        masses = [1.0, spec.wheel_mass_kg, 1.0, spec.wheel_mass_kg, spec.wheel_mass_kg, spec.wheel_mass_kg]
        shapes = [-1, wheel, -1, wheel, wheel, wheel]
        positions = [(front, side, -lift), (0, 0, 0), (front, -side, -lift), (0, 0, 0), (rear, side, -lift),
                     (rear, -side, -lift)]
        parents = [0, 1, 0, 3, 0, 0]
        axes = [(0, 0, 1), (0, 1, 0), (0, 0, 1), (0, 1, 0), (0, 1, 0), (0, 1, 0)]
        n = len(masses)
        self.body = c.createMultiBody(
            baseMass=spec.mass_kg, baseCollisionShapeIndex=chassis,
            basePosition=(x_m, y_m, spec.wheel_radius_m + lift),
            linkMasses=masses, linkCollisionShapeIndices=shapes, linkVisualShapeIndices=[-1] * n,
            linkPositions=positions, linkOrientations=[(0, 0, 0, 1)] * n,
            linkInertialFramePositions=[(0, 0, 0)] * n, linkInertialFrameOrientations=[(0, 0, 0, 1)] * n,
            linkParentIndices=parents, linkJointTypes=[p.JOINT_REVOLUTE] * n, linkJointAxis=axes)
        self.steer_joints, self.wheel_joints = [0, 2], [1, 3, 4, 5]
        for joint in self.wheel_joints:
            c.changeDynamics(self.body, joint, lateralFriction=1.0, rollingFriction=0.0, spinningFriction=0.0)
        for link in range(-1, n):
            for other in range(link + 1, n):
                c.setCollisionFilterPair(self.body, self.body, link, other, 0)
        self.wheel_target_mps = 0.0
        # the calls made on every control step, bound once (BulletClient looks each one up by name otherwise)
        own = {"physicsClientId": c._client}
        self._position = functools.partial(p.getBasePositionAndOrientation, self.body, **own)
        self._velocity = functools.partial(p.getBaseVelocity, self.body, **own)
        self._euler = functools.partial(p.getEulerFromQuaternion, **own)
        self._motors = functools.partial(p.setJointMotorControlArray, self.body, **own)

    def pose(self) -> Pose:
        (x, y, _), orientation = self._position()
        yaw = self._euler(orientation)[2]
        (vx, vy, _), _ = self._velocity()
        return Pose(x, y, yaw, vx * math.cos(yaw) + vy * math.sin(yaw))

    def command(self, speed_mps: float, steer_rad: float, dt_s: float) -> None:
        """Drive towards ``speed_mps`` within the acceleration/braking limits; steer the front wheels."""
        step_up, step_down = self.spec.max_accel_mps2 * dt_s, self.spec.max_brake_mps2 * dt_s
        delta = speed_mps - self.wheel_target_mps
        self.wheel_target_mps += max(-step_down, min(step_up, delta))
        omega = self.wheel_target_mps / self.spec.wheel_radius_m
        self._motors(self.wheel_joints, p.VELOCITY_CONTROL, targetVelocities=[omega] * 4,
                     forces=[self.spec.wheel_force_n] * 4)
        steer = max(-self.spec.max_steer_rad, min(self.spec.max_steer_rad, steer_rad))
        self._motors(self.steer_joints, p.POSITION_CONTROL, targetPositions=[steer] * 2, forces=[5000.0] * 2)

    def shift_x(self, dx_m: float) -> None:
        """Re-centre the world: move the whole car by ``dx_m`` keeping every velocity (bookkeeping, not control)."""
        c = self.scene.client
        (x, y, z), orientation = c.getBasePositionAndOrientation(self.body)
        linear, angular = c.getBaseVelocity(self.body)
        c.resetBasePositionAndOrientation(self.body, (x + dx_m, y, z), orientation)
        c.resetBaseVelocity(self.body, linear, angular)


class KinematicCar:
    """Another vehicle: a car-sized box moved at constant speed along its lane, with real contacts."""

    def __init__(self, scene: Scene, x_m: float, y_m: float, velocity_mps: float, spec: CarSpec = CAR) -> None:
        self.scene, self.velocity_mps = scene, velocity_mps
        half = (spec.length_m / 2, spec.width_m / 2, spec.height_m / 2)
        shape = scene.client.createCollisionShape(p.GEOM_BOX, halfExtents=half)
        self.body = scene.client.createMultiBody(0, shape, basePosition=(x_m, y_m, spec.height_m / 2 + 0.05))
        self.x_m, self.y_m, self.z_m = x_m, y_m, spec.height_m / 2 + 0.05
        self.respawns = 0  # a respawned car is a new vehicle: its old predictions no longer apply

    def place(self, x_m: float) -> None:
        self.x_m = x_m
        self.scene.place(self.body, (x_m, self.y_m, self.z_m))

    def advance(self, dt_s: float) -> None:
        self.place(self.x_m + self.velocity_mps * dt_s)


def first_contact(scene: Scene, body: int, cars: Iterable[KinematicCar]) -> KinematicCar | None:
    """The first of ``cars`` (in their order) touching ``body`` after the last physics step, or None."""
    touching = scene.touching(body)
    return next((car for car in cars if car.body in touching), None)
