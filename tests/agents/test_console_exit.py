"""agents.cli.console_main (the ``faultmas`` script) ends the process without the interpreter's teardown, but as
the interpreter would end it otherwise: atexit handlers run, buffered output arrives, the exit status is
main's, a non-daemon thread left running is joined. Each case is a fresh interpreter."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap


def _console(code: str, *argv: str) -> subprocess.CompletedProcess:
    prelude = f"import sys; sys.argv = ['faultmas', *{list(argv)!r}]\n"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}     # output buffered, as usual
    return subprocess.run([sys.executable, "-c", prelude + textwrap.dedent(code)], capture_output=True, text=True,
                          timeout=120, env=env)


def test_atexit_handlers_run_and_buffered_output_arrives():
    done = _console("""
        import atexit
        from agents.cli import console_main
        atexit.register(lambda: print("atexit ran"))
        sys.stdout.write("x" * 100_000)          # more than any buffer: flushed before the process ends
        console_main()
    """, "--version")
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("x" * 100_000) and "faultmas " in done.stdout
    assert done.stdout.rstrip().endswith("atexit ran")


def test_the_exit_status_is_mains():
    done = _console("from agents.cli import console_main; console_main()", "asl", "run", "/nonexistent/x.asl")
    assert done.returncode == 2 and "cannot read" in done.stderr
    usage = _console("from agents.cli import console_main; console_main()", "no-such-command")
    assert usage.returncode == 2 and "invalid choice" in usage.stderr


def test_a_non_daemon_thread_left_running_is_joined():
    done = _console("""
        import threading, time
        from agents.cli import console_main
        threading.Thread(target=lambda: (time.sleep(0.5), print("thread finished", flush=True))).start()
        console_main()
    """, "--version")
    assert done.returncode == 0, done.stderr
    assert "thread finished" in done.stdout


def test_the_garbage_collector_still_runs():
    done = _console("""
        import gc
        from agents import cli
        def check():
            assert gc.isenabled() and gc.get_threshold()[0] == cli.GC_THRESHOLD
            class Cycle: pass
            a, b = Cycle(), Cycle(); a.b, b.a = b, a
            del a, b
            assert gc.collect() > 0
            print("collected")
            return 0
        cli.main = lambda: check()
        cli.console_main()
    """)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "collected"
