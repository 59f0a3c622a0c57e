"""``faultmas router``: a Zenoh router in a Python process, for MAS that span several hosts.

Each host's agents connect to a router (``--connect tcp/HOST:PORT``) and routers connect to each
other. It listens on loopback (``tcp/127.0.0.1:7447``) unless told otherwise, so a router started
by mistake exposes nothing; pass ``--listen tcp/0.0.0.0:7447`` (better: a ``tls/`` endpoint and
``--config`` with certificates and access control, see docs/deployment.md) to serve other hosts.
"""
from __future__ import annotations

import argparse
import signal
import sys
import threading
from typing import Any, Sequence

DEFAULT_LISTEN = "tcp/127.0.0.1:7447"


def add_router_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``faultmas router`` on the CLI dispatcher's sub-parsers."""
    parser = subparsers.add_parser("router", help="run a Zenoh router for multi-host MAS",
                                   description=__doc__.splitlines()[0])
    _add_arguments(parser)
    parser.set_defaults(func=run_router)
    return parser


def _add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--listen", action="append", default=None, metavar="ENDPOINT",
                        help=f"endpoint to listen on, repeatable (default {DEFAULT_LISTEN})")
    parser.add_argument("--connect", action="append", default=[], metavar="ENDPOINT",
                        help="another router to connect to, repeatable")
    parser.add_argument("--config", default=None, metavar="FILE",
                        help="Zenoh JSON5 configuration (TLS, user/password, access control)")
    parser.add_argument("--timeout", type=float, default=None, metavar="S",
                        help="stop after S seconds (default: run until interrupted)")


def start_failure(endpoints: list[str], error: str) -> str:
    """Zenoh's error as one line a person can act on: without the Rust source paths it carries, and with what
    to do when the port is taken (the usual case)."""
    import re

    where = " ".join(endpoints)
    if "Address already in use" in error:
        return (f"cannot listen on {where}: the port is already in use (another router or program); "
                f"choose another with --listen, e.g. tcp/127.0.0.1:7448")
    plain = re.sub(r"\s*at /\S+\.rs:\d+\.?", "", error).replace("[", "").replace("]", "").strip()
    return f"cannot start on {where}: {plain}"


def run_router(args: argparse.Namespace) -> int:
    """Open the router session and keep it until SIGINT/SIGTERM, end of ``--timeout``; exit code."""
    import zenoh

    from agents.transport.config import ZenohOptions, build_config, listen_endpoints

    listen = tuple(args.listen) if args.listen else (None if args.config else (DEFAULT_LISTEN,))
    try:
        config = build_config(ZenohOptions(mode="router", listen=listen, connect=tuple(args.connect),
                                           config_file=args.config))
    except ValueError as exc:
        print(f"faultmas router: {exc}", file=sys.stderr)
        return 2
    try:
        session = zenoh.open(config)
    except zenoh.ZError as exc:
        print(f"faultmas router: {start_failure(listen_endpoints(config), str(exc))}", file=sys.stderr)
        return 1
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())
    print(f"faultmas router {session.info.zid()} listening on {' '.join(listen_endpoints(config))}",
          flush=True)
    try:
        stop.wait(args.timeout)
    finally:
        session.close()
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m agents.router", description=__doc__.splitlines()[0])
    _add_arguments(parser)
    return run_router(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
