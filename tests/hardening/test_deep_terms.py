"""Issue 22: terms an agent builds at run time, level after level, past what any parsed clause may nest
(``nesting.MAX_NESTING`` guards only what is parsed). A goal that wraps its argument 190 levels deeper on
each call reached 19,000 levels and the compiled interpreter overflowed the C stack in ``terms.resolve``
(SIGSEGV: the agent gone without a log line; found hunting the SIGSEGV of the first long fuzz run). Now
``resolve`` refuses to build a term deeper than ``terms.MAX_TERM_DEPTH``: the intention fails with a reason
and the agent goes on, compiled or from source. Each program runs in a child process (a crash must not take
the test run with it)."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
WRAP = "f(" * 190 + "T" + ")" * 190
# terms that resolve themselves (a name-space term with an unbound name space, a plan term): ``resolve`` once
# started a new count inside each, so nesting one at every level was bounded only by what built it (19,000
# levels: SIGSEGV of the compiled build); the count now goes on through them
NS_WRAP = "NS::f(" * 95 + "T" + ")" * 95
PLAN_WRAP = "{ +b(" * 45 + "P" + ") }" * 45
PROGRAMS = {
    # a goal that wraps its argument deeper on each call (each clause nests 191 levels: allowed)
    "goal": f"+!g(0, T) <- .print(T).\n+!g(N, T) <- D = {WRAP}; !g(N-1, D).\n"
            "+!start <- !g(100, a).\n",
    # a list inside a list inside ..., one level per call
    "list": "+!g(0, L) <- .print(L).\n+!g(N, L) <- !g(N-1, [L]).\n+!start <- !g(20000, []).\n",
    # the same through name-space terms (their name space unbound: each stays a term of its own)
    "namespace": f"+!g(0, T) <- .print(done).\n+!g(N, T) <- D = {NS_WRAP}; !g(N-1, D).\n"
                 "+!start <- !g(100, a).\n",
    # plan terms in plan terms: the goal's argument wraps the last one 45 plan terms deeper on each call
    "plan_term": f"+!g(0, P) <- .print(done).\n+!g(N, P) <- !g(N-1, {PLAN_WRAP}).\n+!start <- !g(400, x).\n",
    # a rule whose answer nests one level per step, resolved when printed
    "rule": "nest(0, a).\nnest(N, f(X)) :- N > 0 & nest(N-1, X).\n+!start <- ?nest(3000, T); .print(T).\n",
}
TAIL = ("!start.\n-!start[error(E), error_msg(M)] <- .print(\"failed: \", E, \" \", M); !after.\n"
        "+!after <- .print(\"still running\").\n")


@pytest.mark.parametrize("pure", [False, True], ids=["compiled-if-built", "from-source"])
@pytest.mark.parametrize("program", sorted(PROGRAMS))
def test_a_term_built_too_deep_at_run_time_fails_its_intention_not_the_agent(tmp_path, program, pure):
    source = tmp_path / f"deep_{program}.asl"
    source.write_text(PROGRAMS[program] + TAIL)
    env = dict(os.environ, PYTHONPATH=str(REPO))
    env.pop("FAULTMAS_PURE_PYTHON", None)
    if pure:
        env["FAULTMAS_PURE_PYTHON"] = "1"
    child = subprocess.run([sys.executable, "-X", "faulthandler", "-m", "agents", "asl", "run", str(source),
                            "--timeout", "120"], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=240)
    assert child.returncode == 0, f"the agent died (exit {child.returncode}): {child.stderr[-2000:]}"
    assert "failed: wrong_arguments a term" in child.stdout, (child.stdout[-1000:], child.stderr[-2000:])
    assert "still running" in child.stdout
