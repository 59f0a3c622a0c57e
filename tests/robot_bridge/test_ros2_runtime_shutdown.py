"""A node's error while rclpy's signal handler shuts its context down (from another thread) is the
shutdown, not a defect: no traceback at the end of a run; an error while the context stays up is raised."""
from __future__ import annotations

import threading
import time

from robot_bridge.ros2.runtime import _not_shutting_down


class _Context:
    """Stands for the ``rclpy`` module: only ``ok()`` is read."""

    def __init__(self) -> None:
        self.up = True

    def ok(self) -> bool:
        return self.up


def test_an_error_during_shutdown_is_the_shutdown_and_one_while_up_is_real():
    context = _Context()
    assert _not_shutting_down(context, grace_s=0.2)                  # stays up: a real error
    threading.Timer(0.1, lambda: setattr(context, "up", False)).start()
    started = time.monotonic()
    assert not _not_shutting_down(context, grace_s=5.0)               # goes down within the grace
    assert time.monotonic() - started < 4.0
