"""``faultmas run --inspect``: the page served by the run itself, on the run's own Zenoh hub.

The run's process holds the simulator, so the map shows its ground truth beside what each robot
believes (odometry), and the timeline is stamped with simulated time as the run's own lines are. At
the end of the run the agents are kept alive (idle) until Ctrl-C or ``hold`` seconds, so their minds
can still be looked at; then the run ends as usual.
"""
from __future__ import annotations

import sys
import threading
from typing import Any, Callable, TextIO

from agents.inspector import TIMELINE_MARKS


class LiveInspector:
    """Serve the page for one run: ``serve(hub, world)`` when the hub is open, ``hold()`` at its end.
    ``hold``: seconds to wait at the end (None: until Ctrl-C); ``allow_pause``: the run's switch."""

    def __init__(self, host: str, port: int, hold: float | None = None, allow_pause: bool = False,
                 out: TextIO | None = None, timeline_marks: int = TIMELINE_MARKS) -> None:
        """Binds ``host:port`` now, so a port in use fails before the run starts (``OSError``)."""
        from agents.inspector.web import listening_socket

        self.socket = listening_socket(host, port)
        self.hold_seconds, self.allow_pause = hold, allow_pause
        self.timeline_marks = timeline_marks
        self.out = out or sys.stderr
        self.url: str | None = None

    def serve(self, hub: Any, world: Any = None) -> Callable[[], None]:
        """Start the hub and the web server on ``hub``'s session; returns their stop."""
        from agents.inspector.hub import TeamHub
        from agents.inspector.web import WebServer

        truth = clock = None
        if world is not None:
            def truth() -> dict:
                return {name: world.pose(name) for name in world.robots}

            def clock() -> float:
                return world.time
        team = TeamHub(hub.session, hub.mas, clock=clock, truth=truth, transport=hub,
                       timeline_marks=self.timeline_marks).start()
        server = WebServer(team, self.socket).start()
        self.url = server.url
        print(f"faultmas: inspector at {server.url}" + (" (pause/step allowed)" if self.allow_pause else ""),
              file=self.out, flush=True)

        def stop() -> None:
            server.stop()
            team.close()
        return stop

    def hold(self) -> None:
        """At the end of the run: keep everything up until Ctrl-C or ``hold`` seconds."""
        if self.hold_seconds == 0:
            return
        what = "Ctrl-C" if self.hold_seconds is None else f"{self.hold_seconds:g} s or Ctrl-C"
        print(f"faultmas: run finished; the inspector stays at {self.url} until {what}", file=self.out, flush=True)
        try:
            threading.Event().wait(self.hold_seconds)
        except KeyboardInterrupt:
            pass
