"""Running rclpy safely: the missing-ROS hint, isolated contexts, spinning threads, node mains.

Shared by every node, the agent-side bridge and the tests, so each one gets the shutdown order
that works (executor, nodes, context, thread; see the notes, section 6) without repeating it.
"""
from __future__ import annotations

import argparse
import logging
import os
import sys
import threading
import time
from typing import Callable, Sequence

ROS_HINT = ("ROS 2 is not installed: pip install 'faultmas[ros2]', then "
            "pip install --force-reinstall --no-deps lark==1.3.1")


class RosUnavailable(ImportError):
    """rclpy (or its RMW library) cannot be imported; the message is the one-line install hint."""


def require_ros(module_name: str = "") -> None:
    """Import rclpy or fail with the one-line hint (exit 2 when ``module_name`` is ``__main__``)."""
    try:
        import rclpy  # noqa: F401
    except ImportError as exc:
        if module_name == "__main__":
            print(f"error: {ROS_HINT} ({exc})", file=sys.stderr)
            raise SystemExit(2)
        raise RosUnavailable(f"{ROS_HINT} ({exc})") from None


def loopback_env(env: dict[str, str] | None = None) -> dict[str, str]:
    """``env`` (default: ours) with discovery kept on this host unless the user chose otherwise."""
    env = dict(os.environ if env is None else env)
    env.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    env.setdefault("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
    return env


def wait_for(predicate: Callable[[], bool], timeout: float = 10.0, period: float = 0.02) -> bool:
    """Poll ``predicate`` until it holds or ``timeout`` passes (discovery has no fixed delay)."""
    deadline = time.monotonic() + timeout
    while True:
        if predicate():
            return True
        if time.monotonic() >= deadline:
            return False
        time.sleep(period)


class RosContext:
    """One rclpy Context and one SingleThreadedExecutor spinning in a daemon thread.

    Isolated from every other context in the process (own participant, own ``domain_id``), so
    a bridge and the nodes it talks to can share a process, and tests do not leak into each other.
    """

    def __init__(self, domain_id: int | None = None, args: Sequence[str] | None = None) -> None:
        require_ros()
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        self.context = rclpy.Context()
        rclpy.init(args=list(args) if args else None, context=self.context, domain_id=domain_id)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.nodes: list = []
        self._thread = threading.Thread(target=self._spin, daemon=True, name="rclpy-spin")
        self._lock = threading.Lock()
        self._closed = False

    def _spin(self) -> None:
        """``executor.spin()``, except that a callback that raises costs its message or timer tick, not the
        thread: before, one exception in one callback ended every node of the context (logged once, then at
        10, 100... in a row, see ``FailureLog``)."""
        from rclpy.executors import ExternalShutdownException

        from robot_bridge.failure_log import FailureLog

        failures = FailureLog(logging.getLogger(__name__), "rclpy executor: a callback")
        while self.ok() and not getattr(self.executor, "_is_shutdown", False):
            try:
                self.executor.spin_once()
                failures.succeeded()
            except ExternalShutdownException:
                return
            except Exception as exc:
                if not self.ok():   # a context shut down under the executor's feet
                    return
                failures.failed(exc)

    def ok(self) -> bool:
        return self.context.ok() and not self._closed

    def add(self, node):
        """Spin ``node`` (built with ``context=self.context``) in this context's executor."""
        with self._lock:
            self.nodes.append(node)
            self.executor.add_node(node)
        return node

    def start(self) -> "RosContext":
        self._thread.start()
        return self

    def close(self) -> None:
        with self._lock:
            if self._closed:
                return
            self._closed = True
        for node in self.nodes:
            stop = getattr(node, "stop", None)
            if stop:
                stop()
        self.executor.shutdown(timeout_sec=2.0)
        for node in self.nodes:
            node.destroy_node()
        self.context.try_shutdown()
        if self._thread.is_alive():
            self._thread.join(timeout=5.0)

    def __enter__(self) -> "RosContext":
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()


def _not_shutting_down(rclpy, grace_s: float = 1.0) -> bool:
    """Whether the context is still up ``grace_s`` after an error. rclpy's signal handler shuts the
    context down from another thread: a take that fails in that window (seen at the end of a data
    generation run: "Unable to convert call argument '0'") is the shutdown, not a defect."""
    deadline = time.monotonic() + grace_s
    while rclpy.ok():
        if time.monotonic() >= deadline:
            return True
        time.sleep(0.05)
    return False


def run_node(node_factory: Callable[..., object], description: str, argv: Sequence[str] | None = None,
             configure: Callable[[argparse.ArgumentParser], None] | None = None) -> int:
    """The ``main`` of one node process: ``python -m robot_bridge.ros2.X [--robot R] [--ros-args ...]``.

    ``--robot R`` puts the node in namespace ``/R``; ``--ros-args`` (remaps, ``-p`` parameters) are
    handed to rclpy unchanged. SIGINT and SIGTERM stop the node cleanly with exit code 0.
    With ``FAULTMAS_PERFBUGS`` set, the scheduled performance bugs are installed in the node
    (:mod:`robot_bridge.ros2.perfbugs`; the learned detector's experiments).
    """
    from robot_bridge.processes import die_with_parent
    die_with_parent()                       # a node of a launch never outlives it
    require_ros("__main__")
    import rclpy
    from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
    from rclpy.utilities import remove_ros_args

    argv = list(sys.argv[1:] if argv is None else argv)
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--robot", default="", help="robot name; the node runs in namespace /ROBOT")
    parser.add_argument("--domain-id", type=int, default=None, help="ROS_DOMAIN_ID for this node")
    if configure:
        configure(parser)
    options = parser.parse_args(remove_ros_args(args=["prog", *argv])[1:])
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    rclpy.init(args=["prog", *argv], domain_id=options.domain_id)
    node = bugs = None
    try:
        node = node_factory(namespace=f"/{options.robot}" if options.robot else "", options=options)
        from robot_bridge.ros2.perfbugs import install_from_env
        bugs = install_from_env(node, options.robot)
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception:
        if _not_shutting_down(rclpy):
            raise                 # a real error, not a message taken while SIGINT/SIGTERM shut us down
    finally:
        if bugs is not None:
            bugs.stop()
        if node is not None:
            stop = getattr(node, "stop", None)
            if stop:
                stop()
            node.destroy_node()
        rclpy.try_shutdown()
    return 0
