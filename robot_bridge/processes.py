"""Child processes of faultmas: started tied to their parent (``spawn``: a child never outlives the process that
started it, however that one ends), stopped politely, then firmly (``stop_processes``), watched for freezes.

Every process faultmas starts (agent processes of ``faultmas run`` and ``mas run --processes``, ROS 2 nodes,
render workers, recording workers) goes through ``spawn``, and every such child calls ``die_with_parent`` first
thing. Two mechanisms, because neither covers every case alone:

- ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` (Linux): the kernel kills the child when its parent dies, even a SIGKILL
  of the parent, even a child that is itself stopped (SIGSTOP) or stuck in C code. It fires on the death of the
  parent *thread* that forked, so it is armed only for children started from the parent's main thread (a
  worker thread that ends would take its children with it).
- a lifeline pipe: the parent holds its write end (close-on-exec, never written) for its whole life, the child
  inherits the read end and a thread of the child waits on it; the kernel closes the write end when the parent
  dies, however it dies, and the read returns: the child sends itself SIGTERM (its clean stop), then SIGKILL
  after ``LIFELINE_GRACE`` seconds. It covers children started from other threads, and other systems.

The parent's clean-up on its own exit paths (exception, SIGINT, SIGTERM) stays with its owners (``Launcher``,
``Supervisor``, the render pool): these mechanisms are for when that clean-up cannot run.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from typing import Any, Callable, Iterable, Sequence

ESCALATION: tuple[int, ...] = (signal.SIGINT, signal.SIGTERM, signal.SIGKILL)
PARENT_ENV = "FAULTMAS_PARENT"   # "PID:FD:PDEATHSIG" for a child of ``spawn``; removed by ``die_with_parent``
LIFELINE_GRACE = 3.0             # seconds between the SIGTERM and the SIGKILL a child sends itself
_PR_SET_PDEATHSIG = 1
_lifeline_lock = threading.Lock()
_lifeline: tuple[int, int, int] | None = None   # (pid that made it, read end, write end)


def _lifeline_read_end() -> int:
    """The read end of this process's lifeline (made once per process; a fork makes its own)."""
    global _lifeline
    with _lifeline_lock:
        if _lifeline is None or _lifeline[0] != os.getpid():
            read_end, write_end = os.pipe()      # both close-on-exec: no other child keeps the write end
            _lifeline = (os.getpid(), read_end, write_end)
        return _lifeline[1]


def spawn(argv: Sequence[str], **popen: Any) -> subprocess.Popen:
    """``subprocess.Popen(argv, **popen)`` for a child that calls ``die_with_parent`` at its start: it will not
    outlive this process. ``env`` and ``pass_fds`` are extended, not replaced."""
    read_end = _lifeline_read_end()
    env = dict(popen.pop("env", None) or os.environ)
    main = threading.current_thread() is threading.main_thread()
    env[PARENT_ENV] = f"{os.getpid()}:{read_end}:{int(main)}"
    pass_fds = (*popen.pop("pass_fds", ()), read_end)
    return subprocess.Popen(argv, env=env, pass_fds=pass_fds, **popen)


def die_with_parent(parent_env: str = PARENT_ENV) -> bool:
    """In a child of ``spawn``: arrange to end when the parent ends (see the module's docstring); ends now if
    it already has. True if tied; False in a process ``spawn`` did not start (nothing to do). The variable
    is removed, so that this process's own children (started by ``spawn`` or not) do not take its parent for theirs."""
    value = os.environ.pop(parent_env, None)
    if not value:
        return False
    try:
        pid, read_end, pdeathsig = (int(part) for part in value.split(":"))
    except ValueError:
        return False
    _tie(pid, read_end, bool(pdeathsig))
    return True


def die_with_multiprocessing_parent() -> bool:
    """In a ``multiprocessing`` child (spawn or forkserver): the same tie, with the parent's sentinel (a pipe the
    parent holds, as the lifeline) for lifeline. False in a process ``multiprocessing`` did not start."""
    import multiprocessing

    parent = multiprocessing.parent_process()
    if parent is None or parent.pid is None or parent.sentinel is None:
        return False
    _tie(parent.pid, parent.sentinel, False)   # which thread started us is unknown: no PDEATHSIG
    return True


def _tie(pid: int, read_end: int, pdeathsig: bool) -> None:
    if pdeathsig and sys.platform.startswith("linux"):
        _set_pdeathsig(signal.SIGKILL)
    if os.getppid() != pid:          # the parent died before the line above: nobody would tell us
        os._exit(128 + signal.SIGTERM)
    threading.Thread(target=_watch_lifeline, args=(read_end, pid), daemon=True, name="faultmas-lifeline").start()


def _set_pdeathsig(signum: int) -> bool:
    import ctypes

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(_PR_SET_PDEATHSIG, int(signum), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watch_lifeline(read_end: int, parent: int) -> None:
    """Wait for the parent's end (EOF on the lifeline), then stop this process: SIGTERM, then SIGKILL."""
    try:
        while os.read(read_end, 1):
            pass
    except OSError:
        pass
    print(f"faultmas: parent process {parent} ended; process {os.getpid()} ends too", file=sys.stderr, flush=True)
    os.kill(os.getpid(), signal.SIGTERM)
    time.sleep(LIFELINE_GRACE)
    os.kill(os.getpid(), signal.SIGKILL)


def stop_processes(processes: Iterable[subprocess.Popen], grace: float,
                   signals: Sequence[int | None] = ESCALATION) -> None:
    """Send each signal in turn to the processes still running, waiting up to ``grace`` seconds after each.

    ``None`` in ``signals`` sends nothing and only waits (for children already asked to stop another way).
    """
    running = [p for p in processes if p.poll() is None]
    for signum in signals:
        running = [p for p in running if p.poll() is None]
        if not running:
            return
        if signum is not None:
            for proc in running:
                try:
                    proc.send_signal(signum)
                except ProcessLookupError:
                    pass
        deadline = time.monotonic() + grace
        for proc in running:
            try:
                proc.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                pass


def frozen(processes: dict[str, subprocess.Popen]) -> list[str]:
    """The names of the processes stopped now (SIGSTOP, a debugger): alive, yet doing nothing."""
    import psutil

    names = []
    for name, proc in processes.items():
        try:
            if proc.poll() is None and psutil.Process(proc.pid).status() in (psutil.STATUS_STOPPED,
                                                                            psutil.STATUS_TRACING_STOP):
                names.append(name)
        except psutil.Error:  # ended meanwhile
            pass
    return names


class FreezeWatch:
    """Samples ``processes()`` every ``interval`` seconds in a thread of its own and adds up how long each was
    stopped (SIGSTOP): a run that goes wrong or times out names the processes that froze, even if they were
    continued since (a freeze explains a timeout that slowness would not)."""

    def __init__(self, processes: Callable[[], dict[str, subprocess.Popen]], interval: float = 0.5) -> None:
        self.processes = processes
        self.interval = interval
        self.stopped_seconds: dict[str, float] = {}
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._watch, daemon=True, name="faultmas-freeze-watch")

    def __enter__(self) -> "FreezeWatch":
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._done.set()
        self._thread.join(5.0)

    def _watch(self) -> None:
        while not self._done.wait(self.interval):
            for name in frozen(self.processes()):
                self.stopped_seconds[name] = self.stopped_seconds.get(name, 0.0) + self.interval

    def report(self) -> list[tuple[str, float]]:
        """(name, seconds seen stopped) of every process that froze, frozen now or not."""
        return sorted(self.stopped_seconds.items())
