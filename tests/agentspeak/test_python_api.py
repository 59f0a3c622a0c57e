"""Internal actions written in Python with the registry decorator: succeed, fail, bind, backtrack, suspend."""
from __future__ import annotations

import threading
from concurrent.futures import Future

from agentspeak.runtime import LocalRuntime
from agentspeak.stdlib.registry import STDLIB, Registry, Suspend

lib = Registry(dict(STDLIB.actions))
pending: list[Future] = []


@lib.internal_action("mylib.ok", args=0)
def ok(ctx):
    return True


@lib.internal_action("mylib.no", args=0)
def no(ctx):
    return False


@lib.internal_action("mylib.double", args=2)
def double(ctx, x, y):
    return ctx.unify(y, x * 2)


@lib.internal_action("mylib.upto", args=2)
def upto(ctx, n, x):
    for i in range(n):
        if ctx.unify(x, i):
            yield
        else:
            return


@lib.internal_action("mylib.later", args=1)
def later(ctx, x):
    fut: Future = Future()
    pending.append(fut)
    return Suspend(future=fut, on_result=lambda c, value: c.unify(x, value))


def run(source: str) -> list[str]:
    lines: list[str] = []
    rt = LocalRuntime(printer=lambda name, text: lines.append(text))
    agent = rt.add_agent("ag", source)
    agent.registry = lib
    rt.run(timeout=10)
    return lines


def test_succeed_fail_and_bind():
    src = "!g.\n+!g <- mylib.ok; mylib.double(21, X); .print(X); mylib.no; .print(never).\n-!g[error(E)] <- .print(E).\n"
    assert run(src) == ["42", "ia_failed"]


def test_several_solutions_backtrack_in_context_and_for():
    src = """!g.
+!g : mylib.upto(5, X) & X > 2 <- .print(first, X);
   for (mylib.upto(3, Y)) { .print(Y) };
   .findall(Z, mylib.upto(4, Z), L); .print(L).
"""
    assert run(src) == ["first3", "0", "1", "2", "[0,1,2,3]"]


def test_suspends_only_its_intention_until_the_future_resolves():
    pending.clear()
    src = """!a. !b.
+!a <- mylib.later(V); .print(got, V).
+!b <- .print(b1); .print(b2); .print(b3); !resolve.
+!resolve <- .print(resolving).
"""

    def resolver():
        # resolve from another thread once the intention is waiting on its future
        while not pending:
            threading.Event().wait(0.005)
        pending[0].set_result(7)

    lines: list[str] = []
    rt = LocalRuntime(printer=lambda name, text: lines.append(text))
    agent = rt.add_agent("ag", src)
    agent.registry = lib
    t = threading.Thread(target=resolver)
    t.start()
    rt.run(timeout=10)
    t.join()
    assert lines[0] == "b1"  # the suspended intention did not block the other one
    assert sorted(lines) == sorted(["b1", "b2", "b3", "resolving", "got7"])


calls: list[str] = []


@lib.internal_action("mylib.fail_after_events", args=0)
def fail_after_events(ctx):
    """Queues three percept-like events, then fails through a future that is already resolved,
    so the failure reaches the intention while other events wait ahead of its -!g event."""
    from agentspeak.program import ADD, BEL, Trigger
    from agentspeak.terms import Literal
    calls.append("called")
    for i in range(3):
        ctx.agent.post_external(Trigger(ADD, BEL, Literal("seen", (i,))))
    fut: Future = Future()
    fut.set_exception(RuntimeError("motor stalled"))
    return Suspend(future=fut)


def test_a_failed_suspended_action_is_not_run_again_while_its_failure_event_waits():
    # Regression: the failure of a suspended formula put its intention back in the run queue while
    # the -!g event was still queued, so the same formula ran a second time and its late failure
    # then hit whatever the intention was doing by then.
    calls.clear()
    src = """!g.
+seen(I) <- .print(seen, I).
+!g <- mylib.fail_after_events; .print(never).
-!g[error_msg(M)] <- .print(recovered); .wait(50); .print(done).
"""
    lines = run(src)
    assert calls == ["called"]
    assert lines.count("recovered") == 1 and lines[-1] == "done"
    assert "never" not in lines
