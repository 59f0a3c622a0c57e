"""_faultmas_ros_libraries: with the ROS 2 wheels installed, a Python process that never imports ROS starts once
(the wheels' bootstrapper would re-execute it), and one that does import rclpy finds every ROS library, runs
a publisher and a subscriber of its own, and passes the libraries on to its children as the bootstrapper did.

Each case is a fresh interpreter of this venv started as from a user's shell: without the bootstrapper's
guard and ``LD_LIBRARY_PATH`` (pytest's own process may have them, and children inherit them).
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import _faultmas_ros_libraries as ros_libraries
from tests.ros_domain import ros_domain  # noqa: E402

SITE_PACKAGES = Path(sys.prefix, "lib", f"python{sys.version_info[0]}.{sys.version_info[1]}", "site-packages")
pytestmark = pytest.mark.skipif(not (SITE_PACKAGES / "ros_wheels_bootstrapper.pth").exists(),
                                reason="the ROS 2 wheels are not installed here (extra 'ros2')")
DOMAIN = ros_domain(83)     # not the other ROS test modules' domains


def _shell_env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if k not in (ros_libraries.GUARD, "LD_LIBRARY_PATH", ros_libraries.OPT_OUT)}
    return {**env, **extra}


def _python(code: str, env: dict[str, str], timeout: float = 120) -> dict:
    """Run ``code`` in a fresh interpreter of this venv; its last stdout line is JSON."""
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env, capture_output=True, text=True,
                          timeout=timeout, cwd=Path.home() if Path.home().is_dir() else None)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


START = """
    import json, os, sys
    print(json.dumps({"guard": os.environ.get("_ROS_WHEELS_BOOTSTRAP_COMPLETE"),
                      "ld_library_path": os.environ.get("LD_LIBRARY_PATH"),
                      "stand_in": "ros_wheels_bootstrapper" in sys.modules
                                  and not hasattr(sys.modules["ros_wheels_bootstrapper"], "get_ros_paths")}))
"""


def test_the_pth_is_installed_beside_the_bootstrappers_and_runs_first():
    ours = SITE_PACKAGES / "_faultmas_ros_libraries.pth"
    assert ours.read_text().startswith("import _faultmas_ros_libraries")
    assert sorted([ours.name, "ros_wheels_bootstrapper.pth"])[0] == ours.name     # site runs .pth files sorted


def test_a_process_that_never_imports_ros_is_not_re_executed():
    started = _python(START, _shell_env())
    assert started == {"guard": None, "ld_library_path": None, "stand_in": True}


def test_the_bootstrappers_re_exec_can_be_asked_for():
    started = _python(START, _shell_env(FAULTMAS_ROS_REEXEC="1"))
    assert started["guard"] == "1" and started["ld_library_path"] and not started["stand_in"]


ROS_ROUND_TRIP = """
    import collections, json, os, subprocess, sys
    lib = os.path.join(sys.prefix, "lib")
    before = os.environ.get("LD_LIBRARY_PATH")
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from std_msgs.msg import String          # its type support is opened by bare name at run time

    context = Context()
    rclpy.init(context=context, domain_id=DOMAIN)
    node = rclpy.create_node("ros_libraries_test", context=context)
    got = []
    node.create_subscription(String, "/ros_libraries_test", got.append, 10)
    publisher = node.create_publisher(String, "/ros_libraries_test", 10)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    for i in range(200):
        publisher.publish(String(data=f"hello {i}"))
        executor.spin_once(timeout_sec=0.05)
        if got:
            break
    executor.shutdown()
    node.destroy_node()
    rclpy.shutdown(context=context)
    sonames = collections.Counter()
    for path in {line.split()[-1] for line in open("/proc/self/maps") if line.rstrip().endswith(".so")
                 or ".so." in line.rsplit("/", 1)[-1]}:
        if path.startswith(lib + os.sep) and os.sep not in path[len(lib) + 1:]:
            sonames[os.path.basename(path).split(".so")[0]] += 1
    child = subprocess.run([sys.executable, "-c", "import rclpy, json, os; "
                            "print(json.dumps(os.environ.get('_ROS_WHEELS_BOOTSTRAP_COMPLETE')))"],
                           capture_output=True, text=True, timeout=120)
    print(json.dumps({"before": before, "received": got[0].data if got else None,
                      "twice": [name for name, n in sonames.items() if n > 1],
                      "ld_library_path": os.environ.get("LD_LIBRARY_PATH", "").split(os.pathsep),
                      "guard": os.environ.get("_ROS_WHEELS_BOOTSTRAP_COMPLETE"), "lib": lib,
                      "child": child.returncode == 0 and json.loads(child.stdout), "child_err": child.stderr[-2000:]}))
"""


@pytest.mark.timeout(300)
def test_a_process_that_imports_rclpy_loads_the_libraries_talks_and_passes_them_on():
    ran = _python(ROS_ROUND_TRIP.replace("DOMAIN", str(DOMAIN)), _shell_env(), timeout=240)
    assert ran["before"] is None                       # started once, without the bootstrapper's variables
    assert ran["received"] and ran["received"].startswith("hello ")
    assert ran["twice"] == []                          # one copy per soname (two copies crash at exit)
    assert ran["ld_library_path"][0] == ran["lib"] and ran["guard"] == "1"
    assert ran["child"] == "1", ran["child_err"]       # a child inherits them, as from the bootstrapper


def test_an_import_error_of_another_kind_is_not_touched(tmp_path):
    """A missing library that is not one of the ROS wheels' is the extension's own error, unchanged."""
    assert ros_libraries._missing_library(ImportError("libnowhere.so.3: cannot open shared object file: "
                                                      "No such file or directory"), [str(tmp_path)]) is None
    (tmp_path / "libthere.so.3").write_bytes(b"")
    assert ros_libraries._missing_library(ImportError("libthere.so.3: cannot open shared object file: "
                                                      "No such file or directory"), [str(tmp_path)]) \
        == str(tmp_path / "libthere.so.3")
