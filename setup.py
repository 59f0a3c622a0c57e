"""Builds the optional compiled interpreter (agentspeak/_speedups.py says what and why) and the simulated
camera's compiled z-buffer loop (robot_bridge/sim/zbuffer.py); pyproject.toml holds everything else.

The listed modules are compiled unchanged by Cython. Every extension is optional: with no C compiler, or
with FAULTMAS_PURE_PYTHON=1 at build time, the package installs and runs from source. Each built module's
source digest goes into agentspeak/_speedups.json, so a module edited later runs from source (with a
warning) until it is rebuilt: ``make speedups`` or ``python setup.py build_ext --inplace``.
"""
from __future__ import annotations

import json
import os
import runpy
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.command.build_py import build_py
from setuptools.command.editable_wheel import editable_wheel

HERE = Path(__file__).resolve().parent
SPEEDUPS = runpy.run_path(str(HERE / "agentspeak" / "_speedups.py"))
# the simulated camera's z-buffer loop, a .pyx of its own, and its guard (which says why)
ZBUFFER = runpy.run_path(str(HERE / "robot_bridge" / "sim" / "zbuffer.py"))
BUILD_DIR = HERE / "build" / "cython"   # Cython's C files, out of the source tree


def _extensions() -> list[Extension]:
    if SPEEDUPS["pure_requested"]():
        return []
    try:
        from Cython.Build import cythonize
    except ImportError:
        print("faultmas: Cython is not installed; the interpreter runs from source")
        return []
    _forget_stale_translations()
    modules = [Extension(m, [str(SPEEDUPS["source_path"](m, Path("agentspeak")))])
               for m in SPEEDUPS["COMPILED_MODULES"]]
    modules.append(Extension(ZBUFFER["MODULE"], [str(ZBUFFER["SOURCE"].relative_to(HERE))]))
    # annotation_typing off: annotations are documentation here, and Cython would otherwise enforce
    # `-> list` on a function that returns a tuple. nonecheck on: a None where a .pxd declares a C type is an
    # AttributeError, as from source, never a crash. The C files stay out of the source tree.
    extensions = cythonize(modules, language_level=3, quiet=True, nthreads=os.cpu_count() or 1,
                           build_dir=str(BUILD_DIR.relative_to(HERE)),
                           compiler_directives={"annotation_typing": False, "nonecheck": True})
    for extension in extensions:   # set here: cythonize's Extensions do not keep an ``optional`` given to it
        extension.optional = True  # a module the C compiler fails on (or no compiler at all) runs from source
        # the C compiler's warnings on Cython's generated code say nothing to a user (errors still show)
        extension.extra_compile_args = [*extension.extra_compile_args, "-w"]
    return extensions


def _forget_stale_translations() -> None:
    """Cython translates a module again when a file it depends on is newer than its C file, so a removed
    ``.pxd`` goes unnoticed: the old C file (with the old C types) would be compiled while the manifest
    records the new digest. The C file of every module whose digest differs from the last build's goes."""
    built = SPEEDUPS["built_digests"](HERE / "agentspeak")
    for module in SPEEDUPS["COMPILED_MODULES"]:
        source = Path(SPEEDUPS["source_path"](module, HERE / "agentspeak"))
        if built.get(module) != SPEEDUPS["source_digest"](source):
            (BUILD_DIR / source.relative_to(HERE)).with_suffix(".c").unlink(missing_ok=True)


class BuildWithManifest(build_ext):
    """build_ext on every core, then record the digest of each source compiled by this build and remove every
    compiled file it did not make: a module no longer listed, or one whose compile failed (the extensions are
    optional; setuptools then still copies an older build's file from build/lib into the tree)."""

    def finalize_options(self) -> None:
        super().finalize_options()
        if self.parallel is None:
            self.parallel = os.cpu_count() or 1

    def run(self) -> None:
        self.compiled_now: set[str] = set()
        if self.extensions:   # first-time set-up: say what is being built instead of scrolling compiler output
            print(f"faultmas: compiling the interpreter ({len(self.extensions) - 1} modules) and the camera's "
                  f"z-buffer loop with Cython and the C compiler, where the sources changed (optional: without "
                  f"it everything runs from source; a few minutes on 2 cores the first time)", flush=True)
        # each source's digest as it was when the build began: a source edited while the build runs (minutes)
        # must not be recorded as compiled (its module was made from the earlier text); then it runs from source
        sources = {ext.name: SPEEDUPS["source_path"](ext.name, HERE / "agentspeak")
                   for ext in self.extensions if ext.name != ZBUFFER["MODULE"]}
        before = {name: SPEEDUPS["source_digest"](path) for name, path in sources.items()}
        stamps_before = {name: SPEEDUPS["source_stamp"](path) for name, path in sources.items()}
        super().run()
        if not self.extensions:
            return
        zbuffer = Path(self.get_ext_fullpath(ZBUFFER["MODULE"]))
        if ZBUFFER["MODULE"] in self.compiled_now:
            manifest = zbuffer.with_name(ZBUFFER["MANIFEST"].name)
            manifest.write_text(json.dumps({"digest": ZBUFFER["source_digest"]()}) + "\n")
        else:
            zbuffer.unlink(missing_ok=True)
        built = {name: digest for name, digest in before.items() if name in self.compiled_now}
        package_dir = Path(self.get_ext_fullpath("agentspeak.terms")).parent   # the tree, or the wheel's
        stamps = {m: stamps_before[m] for m in built}
        record = {**built, SPEEDUPS["STAMPS"]: stamps}    # stamps: the quick check at every start (_speedups.py)
        (package_dir / SPEEDUPS["MANIFEST"]).write_text(json.dumps(record, indent=1, sort_keys=True) + "\n")
        for module, compiled in SPEEDUPS["compiled_files"](package_dir).items():
            if module not in built:   # not made by this build from the source on disk: never imported, so gone
                os.remove(compiled)
                print(f"faultmas: removed the compiled {module} of an older build")
        print(f"faultmas: {len(built)} of {len(self.extensions) - 1} interpreter modules compiled; camera "
              f"z-buffer loop {'compiled' if zbuffer.exists() else 'not compiled (numpy draws)'}")

    def build_extension(self, ext: Extension) -> None:
        super().build_extension(ext)
        self.compiled_now.add(ext.name)   # reached when it compiled, or was up to date with its (current) C file


# _faultmas_ros_libraries.py says why: this .pth keeps the ROS 2 wheels from re-executing every interpreter
ROS_LIBRARIES_PTH = HERE / "_faultmas_ros_libraries.pth"


class BuildPyWithPth(build_py):
    """build_py, plus the ``.pth`` at the root of the wheel (site-packages), where only a ``.pth`` runs."""

    def run(self) -> None:
        super().run()
        if not self.editable_mode:
            self.copy_file(str(ROS_LIBRARIES_PTH), str(Path(self.build_lib) / ROS_LIBRARIES_PTH.name))

    def get_outputs(self, include_bytecode: bool = True) -> list[str]:
        return [*super().get_outputs(include_bytecode), str(Path(self.build_lib) / ROS_LIBRARIES_PTH.name)]


class EditableWheelWithPth(editable_wheel):
    """The editable install (``pip install -e``, the Makefile's) with the same ``.pth``: setuptools' strategies
    write only their own files into the editable wheel, so the chosen one is wrapped. ``_select_strategy`` is
    setuptools' own (84): were it gone, the editable install would lack the ``.pth`` and the ROS wheels would
    re-execute every interpreter again, slower but correct."""

    def _select_strategy(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        return _StrategyWithPth(super()._select_strategy(*args, **kwargs))


class _StrategyWithPth:
    def __init__(self, strategy) -> None:  # type: ignore[no-untyped-def]
        self.strategy = strategy

    def __call__(self, wheel, files, mapping) -> None:  # type: ignore[no-untyped-def]
        self.strategy(wheel, files, mapping)
        wheel.writestr(ROS_LIBRARIES_PTH.name, ROS_LIBRARIES_PTH.read_bytes())

    def __enter__(self) -> "_StrategyWithPth":
        self.strategy.__enter__()
        return self

    def __exit__(self, *exc) -> object:  # type: ignore[no-untyped-def]
        return self.strategy.__exit__(*exc)


commands = {"build_ext": BuildWithManifest, "build_py": BuildPyWithPth}
if hasattr(editable_wheel, "_select_strategy"):
    commands["editable_wheel"] = EditableWheelWithPth
setup(ext_modules=_extensions(), cmdclass=commands)
