"""Fork/join: ``A |&| B`` waits for every branch, ``A ||| B`` for the first (Jason's .fork/.join).

Each branch runs as its own intention with a copy of the caller's bindings; the caller is suspended
until the join. Bindings made by the finishing branch(es) are merged back into the caller.
"""
from __future__ import annotations

from agentspeak.intentions import IntendedMeans, Intention
from agentspeak.program import ACHIEVE, ADD, Plan, Trigger
from agentspeak.terms import Literal


class ForkGroup:
    def __init__(self, kind: str, parent: Intention, parent_im: IntendedMeans, instr) -> None:
        self.kind, self.parent, self.parent_im, self.instr = kind, parent, parent_im, instr
        self.branches: list[Intention] = []
        self.done = 0
        self.failed = 0
        self.closed = False

    def branch_done(self, agent, branch: Intention, ok: bool) -> None:
        if self.closed:
            return
        if ok:
            self.done += 1
            self.parent_im.b.update({k: v for k, v in branch_bindings(branch).items() if k not in self.parent_im.b})
        else:
            self.failed += 1
        total = len(self.branches)
        if self.kind == "and":
            if not ok:
                self._close(agent, branch)
                agent._requeue(self.parent)
                agent._fail(self.parent, "fork_failed", f"a branch of '{self.instr}' failed", self.instr)
            elif self.done == total:
                self._close(agent, branch)
                agent._requeue(self.parent)
                agent.clr_int(self.parent)
        else:
            if ok:
                self._close(agent, branch)
                agent._requeue(self.parent)
                agent.clr_int(self.parent)
            elif self.failed == total:
                self._close(agent, branch)
                agent._requeue(self.parent)
                agent._fail(self.parent, "fork_failed", f"every branch of '{self.instr}' failed", self.instr)

    def _close(self, agent, finished: Intention) -> None:
        self.closed = True
        for other in self.branches:
            if other is not finished and not other.dropped:
                other.fork = None
                agent.drop_intention(other)


_FORK_TRIGGER = Trigger(ADD, ACHIEVE, Literal("fork__branch"))


def start_fork(agent, intention: Intention, im: IntendedMeans, frame, instr) -> None:
    frame.pc += 1
    group = ForkGroup(instr.kind, intention, im, instr)
    for body in instr.branches:
        branch = Intention()
        plan = Plan(_FORK_TRIGGER, None, body)
        bim = IntendedMeans(plan, dict(im.b), _FORK_TRIGGER.literal)
        branch.stack.append(bim)
        branch.fork = group
        _remember_bindings(branch, bim)
        group.branches.append(branch)
    agent._suspend(intention, "fork")
    for branch in group.branches:
        agent._requeue(branch)


def _remember_bindings(branch: Intention, im: IntendedMeans) -> None:
    """The bottom intended means' dict is what the branch computes; keep it for the join."""
    _FINAL[id(branch)] = im.b


_FINAL: dict[int, dict] = {}


def branch_bindings(branch: Intention) -> dict:
    return _FINAL.pop(id(branch), {})
