"""The ROS 2 wheels' native libraries, loaded when a ROS module first needs them instead of at every start.

The ROS 2 wheels (``faultmas[ros2]``) install ``ros_wheels_bootstrapper.pth``: at every start of every
interpreter of the environment it sets ``LD_LIBRARY_PATH`` (``<prefix>/lib`` and the wheels'
``site-packages/ros_*.libs``) and ``os.execve``\\ s the interpreter again, so every Python process pays its
start twice (~40 ms here), although most never import ROS (``faultmas --help``, ``faultmas asl run``, pip,
pytest's workers).

``_faultmas_ros_libraries.pth`` (installed beside it by faultmas's wheel and editable install; its name sorts
first, so it runs first) imports this module, which costs microseconds and:

* puts a stand-in for ``ros_wheels_bootstrapper`` into ``sys.modules``, so its ``.pth`` imports that and does
  nothing (the environment is left as it was: no variable tells children to skip anything);
* wraps the loader of extension modules: when one fails because a shared library of the ROS wheels cannot
  be found (``rclpy._rclpy_pybind11``, a message package's type support), every library of ``<prefix>/lib``
  is loaded by path, each library it needs from those directories first, and the extension is loaded again.
  The ROS libraries name each other without a path (``librcl.so``, and at run time ``rcutils`` opens a
  message's type support by bare name), which the dynamic linker resolves against libraries already loaded
  (by soname) but searches ``LD_LIBRARY_PATH`` only as it was at process start: so all of them are loaded
  at once, one copy per soname (the wheels hold copies, not symlinks, of ``libfastrtps.so``,
  ``libfastrtps.so.2.14``...). Then ``LD_LIBRARY_PATH`` and the bootstrapper's guard are set in
  ``os.environ`` exactly as the bootstrapper would have, for what searches it later (``rcpputils``'
  ``find_library_path``) and for child processes (a child that runs a ROS program is as before).

A process that never imports ROS never loads anything. One that does pays about what the re-exec cost it.
Set ``FAULTMAS_ROS_REEXEC=1`` to let the bootstrapper re-exec as it would without faultmas. Kept at the top
level, stdlib only: a ``.pth`` runs it at every start, before any package could be imported cheaply.
"""
from __future__ import annotations

import _thread
import os
import sys
from importlib.machinery import ExtensionFileLoader

BOOTSTRAPPER = "ros_wheels_bootstrapper"
GUARD = "_ROS_WHEELS_BOOTSTRAP_COMPLETE"          # the bootstrapper's own guard variable
OPT_OUT = "FAULTMAS_ROS_REEXEC"
_MISSING = r"([^\s/:]+\.so[^\s/:]*): cannot open shared object file"   # the dynamic linker's words

_lock = _thread.allocate_lock()                   # (not threading, nor re: this module runs at every start)
_loaded: dict[str, object] = {}                   # file name -> its ctypes handle (kept: never unloaded)
_done = False


def library_dirs() -> list[str]:
    """Where the ROS wheels put their libraries, in the bootstrapper's terms: ``<prefix>/lib``, then every
    ``site-packages/ros_*.libs`` (auditwheel's copies of the system libraries they need)."""
    site_packages = os.path.join(sys.prefix, "lib", f"python{sys.version_info[0]}.{sys.version_info[1]}",
                                 "site-packages")
    try:
        vendored = sorted(os.path.join(site_packages, name) for name in os.listdir(site_packages)
                          if name.startswith("ros_") and name.endswith(".libs"))
    except OSError:
        vendored = []
    return [os.path.join(sys.prefix, "lib"), *vendored]


def _find(name: str, dirs: list[str]) -> str | None:
    return next((os.path.join(d, name) for d in dirs if os.path.isfile(os.path.join(d, name))), None)


def _missing_library(error: BaseException, dirs: list[str]) -> str | None:
    """The library (a path in ``dirs``) whose absence ``error`` reports; None if it is not one of those."""
    if "cannot open shared object file" not in str(error):
        return None
    import re

    match = re.search(_MISSING, str(error))
    return _find(match[1], dirs) if match else None


def _load(path: str, dirs: list[str]) -> None:
    """Load ``path``, and before it each library from ``dirs`` that the dynamic linker reports missing."""
    import ctypes

    name = os.path.basename(path)
    while name not in _loaded:
        try:
            _loaded[name] = ctypes.CDLL(path, mode=ctypes.RTLD_GLOBAL)
        except OSError as error:
            missing = _missing_library(str(error).replace(path, ""), dirs)
            if missing is None or os.path.basename(missing) in _loaded:
                raise
            _load(missing, dirs)


def load_ros_libraries() -> None:
    """Load every ROS library of this environment (one file per soname) and set the environment variables
    the bootstrapper sets. Idempotent; a library that cannot be loaded raises ``OSError``."""
    global _done
    with _lock:
        if _done:
            return
        dirs = library_dirs()
        lib = dirs[0]
        first_of_soname: dict[str, str] = {}        # libfastrtps.so, .so.2.14, .so.2.14.5: copies, one soname
        for name in sorted(os.listdir(lib)):
            if name.startswith("lib") and ".so" in name and os.path.isfile(os.path.join(lib, name)):
                first_of_soname.setdefault(name.split(".so", 1)[0], name)
        for stem, name in first_of_soname.items():
            if not any(loaded.split(".so", 1)[0] == stem for loaded in _loaded):   # (perhaps as another's need)
                _load(os.path.join(lib, name), dirs)
        inherited = [part for part in os.environ.get("LD_LIBRARY_PATH", "").split(os.pathsep) if part]
        os.environ["LD_LIBRARY_PATH"] = os.pathsep.join([*dirs, *(p for p in inherited if p not in dirs)])
        os.environ[GUARD] = "1"
        _done = True


_create_module = ExtensionFileLoader.create_module


def _create_module_loading_ros(self: ExtensionFileLoader, spec):  # type: ignore[no-untyped-def]
    """``ExtensionFileLoader.create_module``, which loads the ROS libraries when the extension needs them."""
    try:
        return _create_module(self, spec)
    except ImportError as error:
        if _done or _missing_library(error, library_dirs()) is None:
            raise
        try:
            load_ros_libraries()
        except OSError as failure:      # still an ImportError: callers test optional imports with that
            raise ImportError(f"{error} (loading the ROS 2 wheels' libraries failed: {failure})",
                              name=spec.name) from failure
    return _create_module(self, spec)


def install() -> None:
    """Called by ``_faultmas_ros_libraries.pth`` at interpreter start (see the module doc)."""
    if os.environ.get(OPT_OUT) == "1":
        return
    stand_in = type(sys)(BOOTSTRAPPER, "faultmas's stand-in: ROS libraries load on first use "
                                              "(_faultmas_ros_libraries)")
    sys.modules.setdefault(BOOTSTRAPPER, stand_in)
    ExtensionFileLoader.create_module = _create_module_loading_ros  # type: ignore[method-assign]
