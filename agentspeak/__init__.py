"""faultmas: agentspeak."""
from agentspeak import _speedups

_speedups.install()  # before any submodule: a stale compiled module must not be imported (see _speedups)
