"""``LoggingBridge``: the smallest complete bridge. It logs each action and says it succeeded.

It is the worked example of ``robot_bridge/README.md`` (how to add a bridge of your own) and a handy
stand-in for dry runs of plans: it checks every action against the vocabulary like a real bridge,
so typos in plans still fail with ``unknown_action`` / ``bad_args``.
"""
from __future__ import annotations

import logging
from concurrent.futures import Future
from typing import ClassVar

from robot_bridge import actions
from robot_bridge.protocol import Action, Completion, Percept, RobotBridge, completed

log = logging.getLogger(__name__)


class LoggingBridge(RobotBridge):
    """Logs actions (and keeps them in ``self.log``); perceives nothing."""

    name: ClassVar[str] = "logging"

    def __init__(self, robot: str, **options: object) -> None:
        super().__init__(robot, **options)
        self.log: list[Action] = []

    def setup(self, timeout: float = 5.0) -> None:
        log.info("%s: logging bridge ready", self.robot)

    def act(self, action: Action) -> "Future[Completion]":
        failure = actions.check(action)
        if failure is not None:
            log.warning("%s: %s fails: %s", self.robot, action, failure.detail)
            return completed(failure)
        self.log.append(action)
        log.info("%s: %s", self.robot, action)
        return completed(Completion.success())

    def percepts(self) -> list[Percept]:
        return []

    def shutdown(self) -> None:
        log.info("%s: logging bridge shut down after %d actions", self.robot, len(self.log))
