"""Presence in the secure profile: a liveliness token is a claim, a signed heartbeat is the proof.

Anyone who can declare a liveliness token can declare one on ``faultmas/<mas>/alive/<name>``: a dead agent
then looked alive (Zenoh reports a key gone only once its *last* token is, so an outsider's token masks the
real one's end), and a name that is no member appeared in the team. In the secure profile each process puts,
every ``HEARTBEAT`` seconds, a heartbeat per local agent signed by that agent's key (``Identity.seal``: a fresh
``seq``, so an old heartbeat put again is refused as a replay); a receiver counts an agent alive while its token
is up *and* a heartbeat (or a status) signed by its key arrived within ``LEASE`` seconds. So an outsider's token
alone never makes anyone alive, and a dead agent whose token is masked is gone at the end of its lease.
``LEASE`` is generous (Zenoh's own link lease is 10 s) so that a process starved of CPU on a loaded machine
does not flicker out of the team; a token withdrawn still ends presence at once.
"""
from __future__ import annotations

import threading
import time
from typing import Callable

HEARTBEAT = 1.0   # seconds between two heartbeats of a local agent
LEASE = 10.0      # seconds a signed heartbeat or status proves an agent alive


class ProvedPresence:
    """Feeds ``update(agent, alive)`` (a ``Presence``'s) from tokens and signed proofs: alive = token up and a
    proof within ``lease`` seconds. ``expire()`` must be called now and then (the heartbeat thread does)."""

    def __init__(self, update: Callable[[str, bool], None], lease: float = LEASE,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self._update, self.lease, self._clock = update, lease, clock
        self._tokens: set[str] = set()
        self._proved_at: dict[str, float] = {}
        self._lock = threading.Lock()

    def token(self, agent: str, up: bool) -> None:
        """A liveliness token of ``agent`` appeared (``up``) or went."""
        with self._lock:
            (self._tokens.add if up else self._tokens.discard)(agent)
        self._refresh(agent)

    def proved(self, agent: str) -> None:
        """A message signed by ``agent``'s key, fresh, arrived (a heartbeat or a status)."""
        with self._lock:
            self._proved_at[agent] = self._clock()
        self._refresh(agent)

    def expire(self) -> None:
        """End the presence of agents whose last proof is older than the lease."""
        with self._lock:
            agents = list(self._tokens | set(self._proved_at))
        for agent in agents:
            self._refresh(agent)

    def _refresh(self, agent: str) -> None:
        with self._lock:
            proved = self._proved_at.get(agent)
            alive = agent in self._tokens and proved is not None and self._clock() - proved <= self.lease
            if proved is not None and agent not in self._tokens and self._clock() - proved > self.lease:
                del self._proved_at[agent]      # forgotten: bounded by the members that were ever proved
        self._update(agent, alive)
