"""What ``faultmas observe`` does (``detection/cli.py`` only declares its arguments)."""
from __future__ import annotations

import argparse
import signal
import sys
import threading
import time

from agentspeak.errors import SourceError
from detection.pipeline import Update
from detection.session import Session, open_session, replay_bag
from detection.status import StatusTable, change_line, json_line


def _printer(args: argparse.Namespace, session: Session):
    """The listener that shows each change, and the table (None unless on a terminal)."""
    if args.json:
        return (lambda u: print(json_line(u), flush=True)), None
    if sys.stdout.isatty() and not args.bag:
        table = StatusTable(session.observers, sys.stdout)
        return table.record, table
    return (lambda u: print(change_line(u), flush=True)), None


def _report_errors(session: Session) -> None:
    obs = session.observers
    for name, n in sorted(obs.errors.items()):
        print(f"faultmas observe: {name}: {n} unreadable message(s) dropped", file=sys.stderr)
    print(f"faultmas observe: {obs.messages} messages observed", file=sys.stderr)


def observe(args: argparse.Namespace) -> int:
    try:
        if args.bag:
            return _replay(args)
        if args.zenoh:
            return _zenoh(args)
        return _live(args)
    except SourceError as exc:
        print(f"faultmas observe: {exc}", file=sys.stderr)
        return 2


def _replay(args: argparse.Namespace) -> int:
    session = open_session(args.config, args.model, args.rules)
    show, _ = _printer(args, session)
    session.pipeline.add_listener(show)
    try:
        replay_bag(session, args.bag)
    except KeyboardInterrupt:
        pass
    finally:
        session.close()
    _report_errors(session)
    return 0


def _live(args: argparse.Namespace) -> int:
    from robot_bridge.ros2.runtime import RosUnavailable, require_ros
    try:
        require_ros()
    except RosUnavailable as exc:
        print(f"faultmas observe: {exc}", file=sys.stderr)
        return 3
    from diagnosis.actions import ActionEnvironment
    from detection.taps.bag import BagRecorder
    from detection.taps.ros2 import Ros2Tap, TapError, info_publisher
    from detection.taps.ros2_parameters import Ros2Parameters

    environment = ActionEnvironment()
    session = open_session(args.config, args.model, args.rules, environment)   # bad input: before any network
    tap = None
    try:
        show, table = _printer(args, session)
        tap = Ros2Tap(session.config, session.observers, session.pipeline.observe, domain_id=args.domain_id)
        if args.record:
            tap.recorder = BagRecorder(args.record)
        environment.parameters = Ros2Parameters(args.domain_id)
        session.pipeline.add_listener(info_publisher(tap))
        session.pipeline.add_listener(show)
        tap.start()
        _run_until_stopped(args, table)
    except TapError as exc:
        print(f"faultmas observe: {args.config}: {exc}", file=sys.stderr)
        return 2
    finally:
        if tap is not None:
            tap.close()
        if environment.parameters is not None:
            environment.parameters.close()
        session.close()
    _report_errors(session)
    return 0


def _run_until_stopped(args: argparse.Namespace, table) -> None:
    """Until Ctrl-C, SIGTERM or ``--duration``; the table (if any) redrawn four times a second."""
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    end = None if args.duration is None else time.monotonic() + args.duration
    try:
        while not stop.is_set() and (end is None or time.monotonic() < end):
            if table is not None:
                table.draw()
            stop.wait(0.25)
    except KeyboardInterrupt:
        pass


def _zenoh(args: argparse.Namespace) -> int:
    from detection.taps.zenoh import ZenohTap

    if args.record:
        print("faultmas observe: --record records ROS 2 topics; it cannot be used with --zenoh", file=sys.stderr)
        return 2
    session = open_session(args.config, args.model, args.rules)
    tap = None
    try:
        show, table = _printer(args, session)
        tap = ZenohTap(session.config, session.observers, session.pipeline.observe, connect=args.connect)
        session.pipeline.add_listener(tap.info_publisher())
        session.pipeline.add_listener(show)
        tap.start()
        _run_until_stopped(args, table)
    finally:
        if tap is not None:
            tap.close()
        session.close()
    _report_errors(session)
    return 0


__all__ = ["observe", "Update"]
