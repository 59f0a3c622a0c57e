"""One name, one agent across the processes of a MAS: claims on a name made at run time (issue 22).

Jason's ``LocalRuntimeServices.createAgent`` holds a lock around ``getNewAgentName`` and adding the agent, so of two
agents that make ``bob`` at once one gets ``bob``, the other ``bob_1``. The processes of a MAS share no lock, and
seeing another process's agent takes the milliseconds its liveliness token takes to travel: two processes that made
one name within them both got it (9 to 11 rounds of 20 in ``tests/agents/test_runtime_agents.py``), and the name's
messages reached both agents. A claim decides instead:

1. A process records its claim on the name (pending), and only then asks every process of the MAS which claims they
   hold on it (``Transport._ask_claims``: a Zenoh query that each process answers from its own table, ``held``).
   Of two processes that claim at the same moment at least one sees the other's claim: each records before it asks,
   and answers from what it has recorded (store, then load; the links keep order).
2. A claimant is (creator agent, process id) and claimants are ordered. A process **loses** the name if it sees a
   claim already won (an agent of that name lives: its claim is held as long as the agent) or a pending claim that
   sorts before its own. It **waits** while it sees pending claims that sort after its own, asking again every
   ``CLAIM_POLL`` seconds: a claimant that saw this claim withdraws (it lost), and one that did not see it was
   first and wins; so this process wins once each has withdrawn, and loses as soon as one has won. Seeing none
   of either, it **wins**. A loser takes the next name, ``Name_1``, ``Name_2``..., as Jason's getNewAgentName
   gives a name that is taken (an explicit name too: Jason's ``.create_agent(bob, ...)`` makes ``bob_1`` when
   there is a ``bob``, and succeeds).

So of two claims made at the same moment (each sees the other) the one whose creator's name sorts first gets the
name, and of two one of which did not see the other, the earlier: as under Jason's lock, the name goes to one
creator, and the other's agent gets the next, every process agreeing. A process only waits on claimants that sort
after it, so no two wait on each other, and each claim is decided in a round trip or two to every process (a
millisecond on loopback). One that cannot be decided within ``CLAIM_TIMEOUT`` (a process of the MAS that stays
connected but does not answer; one that died or was cut off is dropped by Zenoh within the link lease, 1 s) fails
with ``NameUndecided``, the claim withdrawn: the creating formula fails saying why, it never hangs.

Processes that cannot reach each other (a network cut in two) cannot agree on anything: each side may give the name
once. Within one process, or with nobody to ask, a claim is decided at once (no settle time).
"""
from __future__ import annotations

import json
import secrets
import threading
import time
from typing import Callable, NamedTuple

from agents.transport.envelope import BadMessage, is_valid_name

CLAIM_TIMEOUT = 5.0
"""Seconds a claim may take to be decided before the creating formula fails (the creator's process waits that long
at most, only for a process of the MAS that is connected and does not answer)."""

CLAIM_POLL = 0.003
"""Seconds between two asks while a claim waits for those of claimants that sort after it to be decided."""

CLAIM_DROP_REASONS = ("bad_claim",)
"""A process's answer about its claims that cannot be read (counted and logged as a drop, like envelopes)."""


class NameUndecided(Exception):
    """A claim on a name could not be decided in time (a process of the MAS did not answer); the claim is withdrawn."""


class Claimant(NamedTuple):
    """Who claims a name: the agent that makes the new one, and its process (``NameClaims.process``). Ordered: of two
    claims that see each other, the one that sorts first wins."""

    creator: str
    process: str


def encode_claim(name: str, claimant: Claimant, won: bool) -> bytes:
    """One process's answer about its claim on ``name``."""
    return json.dumps({"name": name, "creator": claimant.creator, "process": claimant.process, "won": won},
                      separators=(",", ":")).encode()


def decode_claim(payload: bytes, name: str) -> tuple[Claimant, bool]:
    """(claimant, won) from an answer about ``name``; ``BadMessage`` (``bad_claim``) if it is none."""
    try:
        data = json.loads(payload)
    except (ValueError, RecursionError) as exc:
        raise BadMessage("bad_claim", f"not JSON: {str(exc)[:60]}") from None
    if not (isinstance(data, dict) and data.get("name") == name and is_valid_name(data.get("creator"))
            and isinstance(data.get("process"), str) and 0 < len(data["process"]) <= 64
            and isinstance(data.get("won"), bool)):
        raise BadMessage("bad_claim", f"expected {{\"name\": {name!r}, \"creator\", \"process\", \"won\"}}")
    return Claimant(data["creator"], data["process"]), data["won"]


Ask = Callable[[str, float], "dict[Claimant, bool]"]
"""``ask(name, timeout)``: the claims on ``name`` held by the processes of the MAS ({claimant: won}), once every
process has answered; ``NameUndecided`` when not all have within ``timeout`` seconds."""


class NameClaims:
    """The claims of one process (one transport) and how each is decided (see the module's docstring)."""

    def __init__(self, process: str | None = None) -> None:
        self.process = process or secrets.token_hex(6)
        self._held: dict[str, tuple[Claimant, bool]] = {}   # name -> (claimant, won)
        self._lock = threading.Lock()   # recorded by the claiming thread, read by the threads that answer

    def held(self) -> list[tuple[str, Claimant, bool]]:
        """(name, claimant, won) of every claim this process holds: what it answers others with."""
        with self._lock:
            return [(name, claimant, won) for name, (claimant, won) in self._held.items()]

    def holds(self, name: str) -> bool:
        return name in self._held

    def release(self, name: str) -> None:
        """Withdraw the claim on ``name`` (its agent is gone, or the claim lost): others may have the name."""
        with self._lock:
            self._held.pop(name, None)

    def claim(self, name: str, creator: str, ask: Ask, timeout: float = CLAIM_TIMEOUT) -> bool:
        """True when this process now holds ``name`` (kept until ``release``); False when another process has or gets
        it. ``NameUndecided`` when it cannot be decided within ``timeout`` seconds (the claim withdrawn)."""
        mine = Claimant(creator, self.process)
        with self._lock:
            if name in self._held:
                raise ValueError(f"this process already claims {name!r}")
            self._held[name] = (mine, False)   # recorded before anyone is asked (see the module's docstring)
        try:
            won = self._decide(name, mine, ask, time.monotonic() + timeout)
        except BaseException:
            self.release(name)
            raise
        if won:
            with self._lock:
                self._held[name] = (mine, True)
        else:
            self.release(name)
        return won

    @staticmethod
    def _decide(name: str, mine: Claimant, ask: Ask, deadline: float) -> bool:
        waiting_for: set[Claimant] | None = None   # the pending claims of claimants after us, seen at our first ask
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                pending = ", ".join(f"{c.creator}'s (process {c.process})" for c in sorted(waiting_for or ()))
                raise NameUndecided(f"the claims on {name} of {pending or 'nobody'} still undecided")
            others = {claimant: won for claimant, won in ask(name, remaining).items() if claimant != mine}
            if any(others.values()):
                return False   # an agent of that name lives, or a claimant that did not see ours was first
            if waiting_for is None:
                if any(claimant < mine for claimant in others):
                    return False
                waiting_for = set(others)   # a later claim saw ours: it waits for us, or loses
            else:
                waiting_for &= others.keys()
            if not waiting_for:
                return True
            time.sleep(min(CLAIM_POLL, max(0.0, deadline - time.monotonic())))
