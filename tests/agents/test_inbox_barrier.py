"""``InboxBarriers`` on its own: an action runs once every inbox it waits for has reached its marker, at once when
there is none to wait for, and when an inbox's agent leaves before reaching it; markers of other processes are no
markers (the real channel: ``test_transport_order.py``)."""
from __future__ import annotations

from agents.transport.inbox_barrier import InboxBarriers


class Inboxes:
    """Inboxes that only collect the markers put in them (``None``: that agent has no inbox)."""

    def __init__(self, *agents: str) -> None:
        self.queued: dict[str, list[bytes]] = {agent: [] for agent in agents}

    def put(self, agent: str, attachment: bytes) -> bool:
        if agent not in self.queued:
            return False
        self.queued[agent].append(attachment)
        return True


def test_an_action_waits_for_every_inbox_and_runs_once():
    inboxes = Inboxes("b", "c")
    barriers, ran = InboxBarriers(inboxes.put), []
    barriers.after(["b", "c"], lambda: ran.append("gone"))
    assert ran == []
    barriers.reached("b", inboxes.queued["b"][0])
    barriers.reached("b", inboxes.queued["b"][0])      # the same marker twice counts once
    assert ran == []
    barriers.reached("c", inboxes.queued["c"][0])
    assert ran == ["gone"]


def test_no_inbox_to_wait_for_runs_at_once():
    barriers, ran = InboxBarriers(Inboxes("b").put), []
    barriers.after([], lambda: ran.append(1))
    barriers.after(["nobody"], lambda: ran.append(2))   # an agent without an inbox (gone already)
    assert ran == [1, 2]


def test_an_agent_that_leaves_releases_what_waits_for_its_inbox():
    inboxes = Inboxes("b", "c")
    barriers, ran = InboxBarriers(inboxes.put), []
    barriers.after(["b", "c"], lambda: ran.append("gone"))
    barriers.reached("c", inboxes.queued["c"][0])
    barriers.release("b")
    assert ran == ["gone"]
    barriers.reached("b", inboxes.queued["b"][0])       # reached after all: nothing more
    assert ran == ["gone"]


def test_only_this_processs_markers_are_markers():
    inboxes = Inboxes("b")
    barriers, other = InboxBarriers(inboxes.put), InboxBarriers(inboxes.put)
    barriers.after(["b"], lambda: None)
    other.after(["b"], lambda: None)
    mine, theirs = inboxes.queued["b"]
    assert barriers.is_marker(mine) and not barriers.is_marker(theirs) and not barriers.is_marker(None)
    assert not barriers.is_marker(mine[:-1])
