"""The floor of the start-up benchmark's diagnosis rows: what every command-line tool that diagnoses with python-sat
runs before it reads its first file, and nothing more (``bench_startup`` runs it beside the other two sides).

    python benchmarks/startup_floor.py ARGS...      # parses ARGS, prints nothing

The script's instructions (or seconds) over the floor's are the best whole-process ratio any such tool can reach
on that instance: even one whose own work (reading the netlist, encoding, search, output) cost nothing. Each part,
and why no such tool avoids it:

* this venv's interpreter starting: site-packages and its ``.pth`` files (the ROS 2 wheels' bootstrapper and
  faultmas's stand-in for it, setuptools' distutils hook, the editable install's path) run at every start of
  every Python program of the environment, the python-sat script's as well;
* ``argparse``: its import, and one parser parsing the command line (a parser's first ``gettext`` call imports
  ``locale``; parsing compiles argparse's patterns). Its help formatter is made without ``shutil``, as faultmas
  makes it, so the floor is no higher than faultmas's own way of doing this;
* ``json``: the observations are JSON, so is the answer a caller parses;
* ``pysolvers``: python-sat's compiled solvers (an 8 MB extension), loaded by every use of python-sat, whatever
  part of it is used (faultmas, too, uses only it at these sizes: ``diagnosis/sat.py``);
* no garbage collection and no interpreter teardown (``os._exit``): a tool may skip both, as faultmas does
  (``agents/cli.py``), so the floor does not pay them either.
"""
import gc

gc.disable()

import argparse  # noqa: E402  (after gc.disable: the imports are the floor's work)
import json  # noqa: E402,F401
import os  # noqa: E402
import sys  # noqa: E402

import pysolvers  # noqa: E402,F401


class _Parser(argparse.ArgumentParser):
    def _get_formatter(self) -> argparse.HelpFormatter:
        return self.formatter_class(prog=self.prog, width=78)     # without shutil.get_terminal_size


_Parser(prog="floor").parse_known_args(sys.argv[1:])
sys.stdout.flush()
os._exit(0)
