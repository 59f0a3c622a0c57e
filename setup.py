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
    modules = [Extension(m, [str(SPEEDUPS["source_path"](m, Path("agentspeak")))], optional=True)
               for m in SPEEDUPS["COMPILED_MODULES"]]
    modules.append(Extension(ZBUFFER["MODULE"], [str(ZBUFFER["SOURCE"].relative_to(HERE))], optional=True))
    # annotation_typing off: annotations are documentation here, and Cython would otherwise enforce
    # `-> list` on a function that returns a tuple. nonecheck on: a None where a .pxd declares a C type is an
    # AttributeError, as from source, never a crash. The C files stay out of the source tree.
    return cythonize(modules, language_level=3, quiet=True, nthreads=os.cpu_count() or 1,
                     build_dir=str(BUILD_DIR.relative_to(HERE)), compiler_directives={"annotation_typing": False, "nonecheck": True})


def _forget_stale_translations() -> None:
    """Cython translates a module again when a file it depends on is newer than its C file, so a removed
    ``.pxd`` goes unnoticed: the old C file (with the old C types) would be compiled while the manifest
    records the new digest. The C file of every module whose digest differs from the last build's goes."""
    try:
        built = json.loads((HERE / "agentspeak" / SPEEDUPS["MANIFEST"]).read_text())
    except (OSError, ValueError):
        built = {}
    for module in SPEEDUPS["COMPILED_MODULES"]:
        source = SPEEDUPS["source_path"](module, HERE / "agentspeak")
        if built.get(module) != SPEEDUPS["source_digest"](source):
            (BUILD_DIR / source.relative_to(HERE)).with_suffix(".c").unlink(missing_ok=True)


class BuildWithManifest(build_ext):
    """build_ext on every core, then record the digest of each source that was compiled (and remove compiled
    files of modules an older build compiled and this one does not)."""

    def finalize_options(self) -> None:
        super().finalize_options()
        if self.parallel is None:
            self.parallel = os.cpu_count() or 1

    def run(self) -> None:
        super().run()
        if not self.extensions:
            return
        zbuffer = Path(self.get_ext_fullpath(ZBUFFER["MODULE"]))
        if zbuffer.exists():
            manifest = zbuffer.with_name(ZBUFFER["MANIFEST"].name)
            manifest.write_text(json.dumps({"digest": ZBUFFER["source_digest"]()}) + "\n")
        built = {ext.name: SPEEDUPS["source_digest"](SPEEDUPS["source_path"](ext.name, HERE / "agentspeak"))
                 for ext in self.extensions if ext.name != ZBUFFER["MODULE"] and Path(self.get_ext_fullpath(ext.name)).exists()}
        package_dir = Path(self.get_ext_fullpath("agentspeak.terms")).parent   # the tree, or the wheel's
        (package_dir / SPEEDUPS["MANIFEST"]).write_text(json.dumps(built, indent=1, sort_keys=True) + "\n")
        for module, compiled in SPEEDUPS["compiled_files"](package_dir).items():
            if module not in built:   # left by an older build (a module no longer listed): never imported, so gone
                compiled.unlink()
                print(f"faultmas: removed the compiled {module} of an older build")
        print(f"faultmas: {len(built)} of {len(self.extensions) - 1} interpreter modules compiled; camera "
              f"z-buffer loop {'compiled' if zbuffer.exists() else 'not compiled (numpy draws)'}")


setup(ext_modules=_extensions(), cmdclass={"build_ext": BuildWithManifest})
