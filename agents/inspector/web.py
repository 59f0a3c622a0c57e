"""The inspector's web app (Starlette): the static page, a server-sent event stream, a few JSON routes.

Routes: ``/`` the page; ``/static/*`` its JS and CSS (package data, no build step, no CDN);
``/events?agent=NAME`` server-sent events, one JSON ``view`` per change (at most ``MAX_RATE`` a second)
with the mind of ``NAME`` while the page shows it; ``/api/team``; ``/api/agents/NAME/mind``;
``/api/timeline.json`` (the export: the marks kept, and how many earlier ones were dropped); ``POST /api/agents/NAME/control`` ``{"command": "pause"|"step"|
"resume"}``, which the agent refuses unless its MAS allows it. A POST must be JSON from this page's
own origin, so another web site open in the same browser cannot pause the team.
"""
from __future__ import annotations

import asyncio
import json
import threading
from importlib import resources
from typing import Any

from agents.inspector.hub import TeamHub

MAX_RATE = 5.0        # views per second per page
KEEPALIVE = 10.0      # seconds between comments on an idle stream


def build_app(hub: TeamHub) -> Any:
    from starlette.applications import Starlette
    from starlette.responses import FileResponse, JSONResponse, Response, StreamingResponse
    from starlette.routing import Mount, Route
    from starlette.staticfiles import StaticFiles

    static = resources.files("agents.inspector").joinpath("static")

    async def page(request):
        return FileResponse(str(static.joinpath("index.html")), headers={"Cache-Control": "no-store"})

    async def team(request):
        return JSONResponse(hub.view())

    async def mind(request):
        name = request.path_params["name"]
        state = await asyncio.to_thread(hub.refresh, name)
        return JSONResponse(state) if state is not None else \
            JSONResponse({"error": f"agent {name} did not answer"}, status_code=404)

    async def timeline(request):
        view = hub.view()
        return JSONResponse({"mas": hub.mas, "clock": view["clock"], "marks": view["timeline"],
                             "dropped": view["timeline_dropped"]},
                            headers={"Content-Disposition": f'attachment; filename="{hub.mas}-timeline.json"'})

    async def control(request):
        origin = request.headers.get("origin")
        if origin is not None and origin.split("://", 1)[-1] != request.headers.get("host"):
            return JSONResponse({"ok": False, "error": "requests from another origin are refused"}, status_code=403)
        if request.headers.get("content-type", "").split(";")[0].strip() != "application/json":
            return JSONResponse({"ok": False, "error": "send JSON"}, status_code=415)
        try:
            body = await request.json()
            command = body["command"]
        except (ValueError, KeyError, TypeError):
            return JSONResponse({"ok": False, "error": "expected {\"command\": ...}"}, status_code=400)
        answer = await asyncio.to_thread(hub.control, request.path_params["name"], str(command))
        return JSONResponse(answer)

    async def events(request):
        agent = request.query_params.get("agent") or None
        if agent is not None:
            try:
                hub.watch(agent)
            except ValueError as exc:
                return Response(str(exc), status_code=400)
        return StreamingResponse(_stream(request, hub, agent), media_type="text/event-stream",
                                 headers={"Cache-Control": "no-store", "X-Accel-Buffering": "no"})

    routes = [Route("/", page), Route("/api/team", team), Route("/api/timeline.json", timeline),
              Route("/api/agents/{name}/mind", mind), Route("/api/agents/{name}/control", control, methods=["POST"]),
              Route("/events", events), Mount("/static", StaticFiles(directory=str(static)), name="static")]
    return Starlette(routes=routes)


async def _stream(request: Any, hub: TeamHub, agent: str | None):
    """One page's events: a full view at once, then on every change (rate-limited). Each view carries the timeline
    marks after those sent before (by number: ``TeamHub.view``), so the page appends them."""
    sent_version, sent_marks = -1, 0
    waited = 0.0
    try:
        while not await request.is_disconnected():
            if hub.version != sent_version:
                view = hub.view(agent, sent_marks)
                sent_version = view["version"]
                sent_marks = view["timeline_length"]
                yield f"data: {json.dumps(view, separators=(',', ':'))}\n\n"
                waited = 0.0
            elif waited >= KEEPALIVE:
                yield ": keep-alive\n\n"
                waited = 0.0
            await asyncio.sleep(1.0 / MAX_RATE)
            waited += 1.0 / MAX_RATE
    finally:
        if agent is not None:
            hub.unwatch(agent)


def listening_socket(host: str, port: int):
    """A TCP socket listening on ``host:port`` (0: a free port); ``OSError`` (port taken...) at once."""
    import socket

    sock = socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_STREAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((host, port))
        sock.listen(128)        # a browser may connect before uvicorn's loop runs: it waits in the backlog
    except OSError:
        sock.close()
        raise
    return sock


class WebServer:
    """uvicorn serving ``build_app(hub)`` on ``sock`` (from ``listening_socket``) in a thread of its own."""

    def __init__(self, hub: TeamHub, sock) -> None:
        import uvicorn

        self.hub = hub
        self.socket = sock
        self.host, self.port = sock.getsockname()[:2]
        config = uvicorn.Config(build_app(hub), log_level="warning", lifespan="off",
                                timeout_graceful_shutdown=1)
        self.server = uvicorn.Server(config)
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    def serve_forever(self) -> None:
        """In the calling thread, until Ctrl-C."""
        self.server.run(sockets=[self.socket])

    def start(self) -> "WebServer":
        self._thread = threading.Thread(target=self.serve_forever, name="faultmas-inspect-web", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self.server.should_exit = True
        if self._thread is not None:
            self._thread.join(5.0)
        self.socket.close()
