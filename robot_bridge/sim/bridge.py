"""``SimBridge``: the default bridge, driving one robot of an in-process ``World``.

Several bridges may share one world (pass the same ``world=``): each drives its own robot, one runner
thread paces the shared clock (see ``runner.py`` for how simulated time relates to wall time). Without
``world=`` the bridge makes a private world with just its robot. The contract is exactly
``RobotBridge``'s, so a remote bridge (the simulator in another process) can replace it unchanged.

Options (all optional): ``world``, ``speed`` (0 = as fast as possible), ``seed``, ``x``, ``y``,
``yaw_deg`` (start pose, used when the robot is not in the world yet), ``fault`` (e.g.
``"left_actuator:0.5"``), ``camera`` (mount a camera), ``drive`` (False: nobody runs the clock, the
caller steps the world itself, for deterministic tests).
"""
from __future__ import annotations

import logging
from concurrent.futures import Future
from typing import ClassVar

from robot_bridge import actions
from robot_bridge.protocol import Action, Completion, Percept, RobotBridge, completed
from robot_bridge.sim.runner import WorldRunner, shared_runner
from robot_bridge.sim.world import World

log = logging.getLogger(__name__)


class SimBridge(RobotBridge):
    """One simulated Kobuki (with optional camera) in an embedded world."""

    name: ClassVar[str] = "sim"

    def __init__(self, robot: str, world: World | None = None, speed: float = 0.0, seed: int = 0,
                 x: float = 0.0, y: float = 0.0, yaw_deg: float = 0.0, fault: str = "none",
                 camera: bool = False, drive: bool = True, **options: object) -> None:
        super().__init__(robot, **options)
        if speed < 0:
            raise ValueError(f"speed must be >= 0 (0 = as fast as possible), got {speed!r}")
        self.world = world if world is not None else World(seed=seed)
        self.speed, self.drive = float(speed), drive
        self._placement = dict(x=float(x), y=float(y), yaw_deg=float(yaw_deg), fault=fault, camera=camera)
        self._runner: WorldRunner | None = None
        self._ready = False

    def setup(self, timeout: float = 5.0) -> None:
        """Put the robot into the world (unless already there) and start the shared clock."""
        if self.robot not in self.world.robots:
            self.world.add_robot(self.robot, **self._placement)
        if self.drive:
            self._runner = shared_runner(self.world, self.speed)
            self._runner.acquire()
        self._ready = True

    def act(self, action: Action) -> "Future[Completion]":
        try:
            spec, args = actions.normalize(action)
        except actions.ActionError as exc:
            return completed(Completion.failure(exc.reason, str(exc)))
        if not self._ready:
            return completed(Completion.failure("shutdown", "the bridge is not set up (call setup())"))
        if self._runner is not None and self._runner.error is not None:
            return completed(Completion.failure("shutdown", f"simulator failed: {self._runner.error!r}"))
        log.debug("%s: %s", self.robot, action)
        if spec.motion:
            return self.world.command(self.robot, spec.name, args)
        if spec.name == "set_fault":
            self.world.set_fault(self.robot, f"{args[0]}:{args[1]}")
        elif spec.name == "reset_odometry":
            self.world.reset_odometry(self.robot)
        return completed(Completion.success())

    def percepts(self) -> list[Percept]:
        if not self._ready:
            return []
        return self.world.percepts(self.robot)

    def shutdown(self) -> None:
        if not self._ready:
            return
        self._ready = False
        self.world.cancel_all("shutdown", name=self.robot)
        if self._runner is not None:
            self._runner.release()
            self._runner = None
