"""``faultmas inspect [--mas NAME] [--connect EP] [--project P.mas2j] [--listen 127.0.0.1:PORT]``: the live web
view of a MAS.

It joins the MAS's Zenoh network (``--connect``: a router or any agent's endpoint; ``faultmas run
--inspect`` needs none, it serves the page itself) and serves the page on loopback. A non-loopback
``--listen`` is refused unless ``--public`` says so, and then a warning says who can see the page.
``--project`` of a MAS in the secure profile (its agents' public keys listed) makes the page trust only what
is signed: agents proved alive by their signed heartbeats, ``.progress`` reports, minds and summaries signed by
their agent; ``--identity`` (a private key the project lists) signs pause/step/resume, which the agents of a
secure MAS refuse otherwise. Without ``--project`` the page cannot check anything: it shows every token, report
and mind that anyone on the network puts (a secure MAS's agents still refuse its pause/step).
"""
from __future__ import annotations

import argparse
import ipaddress
import sys
import time

from agents.inspector import TIMELINE_MARKS

DEFAULT_LISTEN = "127.0.0.1:8470"
DISCOVERY = 3.0   # seconds to look for a MAS when --mas is not given


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("inspect", help="a live web view of a running MAS: agents' minds, robots, timeline",
                       description="A live local web page of a running MAS: its agents (alive or gone), each "
                                   "agent's beliefs, events, intentions, plans and messages, the robots on a map, "
                                   "the .diagnose calls and the timeline of the fault-plan steps. "
                                   "See docs/inspector.md.")
    p.add_argument("--mas", default=None, help="the MAS to look at (default: the only one seen)")
    p.add_argument("--connect", action="append", default=[], metavar="ENDPOINT",
                   help="a Zenoh router or agent of the MAS, e.g. tcp/127.0.0.1:7447 (repeatable)")
    p.add_argument("--config", default=None, metavar="FILE", help="Zenoh JSON5 file (TLS, access control)")
    p.add_argument("--project", default=None, metavar="FILE.mas2j",
                   help="the MAS's project file; in the secure profile (key= options) only agents proved by "
                        "their signed heartbeats are shown alive and only signed .progress reports join the "
                        "timeline (without it, the page believes every liveliness token and report)")
    p.add_argument("--identity", default=None, metavar="KEY.pem",
                   help="with --project in the secure profile: a private key the project lists (a member's or "
                        "the environment's), to sign pause/step/resume (the agents refuse them unsigned)")
    add_listen_arguments(p)
    p.set_defaults(func=cmd_inspect)


def add_listen_arguments(p: argparse.ArgumentParser) -> None:
    """``--listen``, ``--public`` and ``--timeline-marks``: the page's options, shared with ``faultmas run --inspect``."""
    p.add_argument("--listen", default=DEFAULT_LISTEN, metavar="HOST:PORT",
                   help="where the page is served (default %(default)s; port 0: any free port)")
    p.add_argument("--public", action="store_true",
                   help="allow a --listen address other than loopback (anyone who reaches it sees the team)")
    p.add_argument("--timeline-marks", type=_positive_int, default=TIMELINE_MARKS, metavar="N",
                   help="timeline marks kept, the newest (default %(default)s); the page says how many earlier "
                        "ones were dropped")


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number of at least 1, got {text!r}")
    return value


def parse_listen(text: str, public: bool) -> tuple[str, int]:
    """``HOST:PORT`` (``[v6]:PORT``) -> (host, port); ``ValueError`` saying why it is refused."""
    host, sep, port = text.rpartition(":")
    host = host.strip("[]")
    if not sep or not host or not port.isdigit() or int(port) > 65535:
        raise ValueError(f"--listen expects HOST:PORT, e.g. {DEFAULT_LISTEN}, got {text!r}")
    try:
        loopback = ipaddress.ip_address(host).is_loopback
    except ValueError:
        loopback = host == "localhost"
    if not loopback and not public:
        raise ValueError(f"--listen {text}: not a loopback address; add --public to serve the page there "
                         "(anyone who can reach it sees the team)")
    if not loopback:
        print(f"faultmas inspect: WARNING serving on {host}, not loopback: anyone who can reach it sees "
              "the team (pause/step only if the MAS allows it)", file=sys.stderr)
    return host, int(port)


def cmd_inspect(args: argparse.Namespace) -> int:
    from agents.inspector.hub import TeamHub
    from agents.inspector.web import WebServer, listening_socket
    from agents.mas_cli import setup_logging
    from agents.transport.config import ZenohOptions, build_config

    setup_logging()
    try:
        host, port = parse_listen(args.listen, args.public)
    except ValueError as exc:
        print(f"faultmas inspect: {exc}", file=sys.stderr)
        return 2
    identity = None
    if args.identity is not None and args.project is None:
        print("faultmas inspect: --identity needs --project (the project lists the keys)", file=sys.stderr)
        return 2
    if args.project is not None:
        from agents.transport.identity import IdentityError, project_identity, project_identity_of_key
        from agentspeak.errors import SourceError
        from agentspeak.mas2j import load_mas2j
        try:
            project = load_mas2j(args.project)
            identity = project_identity(project) if args.identity is None else \
                project_identity_of_key(project, args.identity)
        except OSError as exc:
            print(f"faultmas inspect: cannot read {args.project}: {exc.strerror or exc}", file=sys.stderr)
            return 2
        except (IdentityError, SourceError, ValueError) as exc:
            print(exc, file=sys.stderr)
            return 2
        args.mas = args.mas or project.name
        if identity is None:
            print(f"faultmas inspect: {args.project} lists no keys (not the secure profile): the page believes "
                  "every liveliness token and report", file=sys.stderr)
    try:
        sock = listening_socket(host, port)
    except OSError as exc:
        print(f"faultmas inspect: cannot serve on {args.listen}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    import zenoh

    try:
        session = zenoh.open(build_config(ZenohOptions(connect=tuple(args.connect), config_file=args.config)))
    except Exception as exc:  # zenoh.ZError or ValueError: bad endpoint or config
        sock.close()
        print(f"faultmas inspect: cannot join the network: {exc}", file=sys.stderr)
        return 1
    try:
        mas = args.mas or _discover(session)
        if mas is None:
            sock.close()
            return 1
        transport = None
        if identity is not None:   # signatures checked as the MAS's own processes check them
            from agents.transport import ZenohTransport
            transport = ZenohTransport(mas, session=session, identity=identity).open()
        hub = TeamHub(session, mas, transport=transport, timeline_marks=args.timeline_marks).start()
        server = WebServer(hub, sock)
        print(f"faultmas inspect: MAS {mas} at {server.url} (Ctrl-C to stop)", flush=True)
        try:
            server.serve_forever()
        finally:
            hub.close()
            if transport is not None:
                transport.close()
        return 0
    finally:
        session.close()


def _discover(session) -> str | None:
    """The one MAS whose agents are alive on the network (within ``DISCOVERY`` seconds)."""
    seen: set[str] = set()
    deadline = time.monotonic() + DISCOVERY
    while time.monotonic() < deadline:
        for reply in session.liveliness().get("faultmas/*/alive/*", timeout=1.0):
            if reply.ok is not None:
                seen.add(str(reply.ok.key_expr).split("/")[1])
        if seen:
            break
        time.sleep(0.2)
    if len(seen) == 1:
        return seen.pop()
    if not seen:
        print("faultmas inspect: no MAS seen on the network (is --connect the endpoint of its router or of "
              "one of its agents?)", file=sys.stderr)
    else:
        print(f"faultmas inspect: several MAS are running ({', '.join(sorted(seen))}): choose one with --mas",
              file=sys.stderr)
    return None
