"""The ROS domain id of a test module, so that two ROS test modules running at the same time never share one.

One run: ``1 + (pid + offset) % 100``, a different ``offset`` per module. Under pytest-xdist (``make test``
runs two workers) the modules of both workers run at the same time, and two workers' pids are close, so the
same formula could give two modules on two workers the same domain: each worker gets its own slice of
1..100 instead (1..100 keeps Fast DDS off the ephemeral ports)."""
from __future__ import annotations

import os

DOMAINS = 100


def ros_domain(offset: int) -> int:
    """This test process's domain for a module that picked ``offset``: distinct per module that may run while
    another's nodes are up, modulo the slice's width (50 with two workers: 0 and 50 would be the same)."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "")           # "gw0", "gw1"... set by pytest-xdist
    workers = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
    index = int(worker[2:]) if worker.startswith("gw") and worker[2:].isdigit() else 0
    slices = min(max(1, workers), DOMAINS)
    width = DOMAINS // slices
    return 1 + (index % slices) * width + (os.getpid() + offset) % width
