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
    from detection.learned.model import ModelFileError

    problem = _bad_combination(args)
    if problem:
        print(f"faultmas observe: {problem}", file=sys.stderr)
        return 2
    try:
        if args.bag:
            return _replay(args)
        if args.zenoh:
            return _zenoh(args)
        return _live(args)
    except (SourceError, ModelFileError) as exc:
        print(f"faultmas observe: {exc}", file=sys.stderr)
        return 2


def _bad_combination(args: argparse.Namespace) -> str:
    """What is wrong with the options together ('' when nothing)."""
    learned = getattr(args, "learned", None)
    if args.config is None and learned is None:
        return "nothing to observe: give CONFIG.yaml, --learned MODELS_DIR, or both"
    if args.bag and args.zenoh:
        return "--bag replays a recording; it cannot be used with --zenoh"
    if args.config is None and learned is None and (args.bag or args.zenoh):
        return "CONFIG.yaml is needed with " + ("--bag" if args.bag else "--zenoh")
    if args.connect and not (args.zenoh or learned is not None):
        return "--connect goes with --zenoh or --learned"
    return ""


def _replay(args: argparse.Namespace) -> int:
    detector = None
    if getattr(args, "learned", None) is not None:      # bad input: before anything runs
        from detection.learned.observer import TICK_CHANNEL, BagReplay
        from detection.taps.bag import first_tap_data, topic_types
        detector = BagReplay(_learned_models(args), topic_types(args.bag))
        if first_tap_data(args.bag, TICK_CHANNEL) is None:
            print(f"faultmas observe: {args.bag}: no learned ticks in this bag: record it with "
                  "'faultmas observe --learned MODELS_DIR --record PATH'", file=sys.stderr)
            return 2
    session = open_session(args.config, args.model, args.rules)
    if detector is not None and args.model is None:
        session.use_model(_replayed_model(detector, args.bag), args.rules)
    show, _ = _printer(args, session)
    session.pipeline.add_listener(show)
    try:
        replay_bag(session, args.bag, detector)
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
    models = _learned_models(args)                      # bad input: before any network
    session = open_session(args.config, args.model, args.rules, environment)
    tap = learned = None
    try:
        show, table = _printer(args, session)
        # one participant and one subscription per topic for the observers and the learned detector:
        # Fast DDS receives each message once (its receive thread is most of the CPU spent watching)
        tap = Ros2Tap(session.config, session.observers, lambda obs: session.pipeline.observe(obs),
                      domain_id=args.domain_id)
        if args.record:
            tap.recorder = BagRecorder(args.record)
        if models:                                      # before the listeners: without --model it sets the model
            learned = _start_learned(args, models, session, environment, reader=tap.reader,
                                     record=_learned_recording(tap, session) if args.record else None)
        environment.parameters = Ros2Parameters(args.domain_id)
        session.pipeline.add_listener(info_publisher(tap))
        session.pipeline.add_listener(show)
        tap.start()
        if learned is not None:
            learned.open_into(session.pipeline.observe)
        _run_until_stopped(args, table)
    except TapError as exc:
        print(f"faultmas observe: {args.config}: {exc}", file=sys.stderr)
        return 2
    finally:
        if learned is not None:
            learned.close()
        if tap is not None:
            tap.close()
        if environment.parameters is not None:
            environment.parameters.close()
        session.close()
    _report_errors(session)
    return 0


class _LearnedFeed:
    """The learned observer's observations, held until the pipeline (with its listeners) is ready:
    its first tick may come while the rest of ``faultmas observe`` is still starting."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._pending: list = []
        self._target = None
        self.live = None

    def emit(self, observations) -> None:
        with self._lock:
            if self._target is None:
                self._pending.extend(observations)
                return
        self._target(observations)

    def open_into(self, target) -> None:
        with self._lock:
            self._target, pending, self._pending = target, self._pending, []
        if pending:
            target(pending)

    def close(self) -> None:
        if self.live is not None:
            self.live.close()


def _learned_models(args: argparse.Namespace) -> dict:
    """The models of ``--learned`` (none without it); ``ModelFileError`` on a bad directory or file."""
    if getattr(args, "learned", None) is None:
        return {}
    from detection.learned.observer import load_models
    return load_models(args.learned)


def _learned_recording(tap, session: Session):
    """What the learned detector records with ``--record``: its ticks, and the messages of its topics
    that no observer reads (those the observers read are recorded once, by the tap)."""
    observed = set(session.config.topics)

    def record(channel: str, t_ns: int, **kwargs) -> None:
        if channel not in observed:
            tap.record(channel, t_ns, **kwargs)
    return record


def _start_learned(args: argparse.Namespace, models: dict, session: Session, environment, *, reader=None,
                   zenoh_keys=None, record=None) -> _LearnedFeed:
    """The learned ``resource`` observer on the live system, emitting into ``session.pipeline``, sharing
    the observers' ROS 2 ``reader`` or Zenoh session (``zenoh_keys``) when given. Without ``--model``
    the diagnoser's architecture is the one discovered (every watched component, its topics and keys,
    ``resource(C)`` declared), so a ``~resource(C)`` is still diagnosed."""
    from detection.learned.model import ModelFileError
    from detection.learned.watch import LiveLearnedObserver

    feed = _LearnedFeed()
    try:
        live = LiveLearnedObserver(models, _namespaces(models), feed.emit, domain_id=args.domain_id,
                                   skip_unfit=True, zenoh_connect=args.connect, reader=reader,
                                   zenoh_keys=zenoh_keys, record=record)
    except ModelFileError:
        raise
    except ValueError as exc:       # e.g. two teams' nodes in one domain: say so, never watch the wrong one
        raise ModelFileError(f"--learned {args.learned}: {exc}") from None
    for reason in live.unfit.values():
        print(f"faultmas observe: --learned {args.learned}: not watched: {reason}", file=sys.stderr)
    if not live.observer.models:
        live.close()
        raise ModelFileError(f"--learned {args.learned}: no model fits the live system (see above)")
    if args.model is None:
        session.use_model(_discovered_model(live), args.rules, environment)
    feed.live = live
    watched = ", ".join(sorted(live.observer.models))
    print(f"faultmas observe: learned resource observer watching {watched}", file=sys.stderr)
    return feed


def _namespaces(models: dict) -> list[str]:
    """The ROS namespaces the models' topics live in (``/faulty/odom`` -> ``/faulty``)."""
    from detection.learned.observer import model_columns
    return sorted({"/" + t.split("/")[1] for m in models.values() for t in model_columns(m)
                   if t.startswith("/") and t.count("/") >= 2})


def _replayed_model(detector, bag):
    """The architecture a replay diagnoses with, without ``--model``: the one the live run discovered
    (recorded in the bag), else the models' components with the topics they read."""
    from detection.learned.observer import COMPONENTS_CHANNEL
    from detection.learned.ros_tap import Component
    from detection.learned.watch import architecture_yaml
    from detection.taps.bag import first_tap_data
    from diagnosis.architecture_yaml import load_architecture
    from diagnosis.yaml_source import YamlSource

    recorded = first_tap_data(bag, COMPONENTS_CHANNEL) or {}
    components = [Component(c, **recorded[c]) if c in recorded else Component(c, "", c, [t for t, _ in chans], [])
                  for c, chans in detector.observer.channels.items()]
    return load_architecture(YamlSource(f"<discovered by --learned, recorded in {bag}>",
                                        architecture_yaml("observed", components)))


def _discovered_model(live):
    from detection.learned.watch import architecture_yaml
    from diagnosis.architecture_yaml import load_architecture
    from diagnosis.yaml_source import YamlSource

    watched = [live.components[c] for c in live.observer.models]
    return load_architecture(YamlSource("<discovered by --learned>", architecture_yaml("observed", watched)))


def _run_until_stopped(args: argparse.Namespace, table) -> None:
    """Until Ctrl-C, SIGTERM or ``--duration``; the table (if any) redrawn four times a second."""
    stop = threading.Event()
    # SIGINT too, set here: a process started without job control (a script's `&`, some CI runners) inherits
    # SIGINT ignored, and Python then never raises KeyboardInterrupt: `kill -INT` must still end the watch
    for signum in (signal.SIGTERM, signal.SIGINT):
        signal.signal(signum, lambda *_: stop.set())
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
    models = _learned_models(args)                      # bad input: before any network
    if models:
        from robot_bridge.ros2.runtime import RosUnavailable, require_ros
        try:
            require_ros()                               # the learned components are ROS 2 nodes (agents too)
        except RosUnavailable as exc:
            print(f"faultmas observe: {exc}", file=sys.stderr)
            return 3
    session = open_session(args.config, args.model, args.rules)
    tap = learned = None
    try:
        show, table = _printer(args, session)
        tap = ZenohTap(session.config, session.observers, lambda obs: session.pipeline.observe(obs),
                       connect=args.connect)
        if models:                                      # the agents' keys through the tap's one Zenoh session
            learned = _start_learned(args, models, session, None, zenoh_keys=tap.keys)
        session.pipeline.add_listener(tap.info_publisher())
        session.pipeline.add_listener(show)
        tap.start()
        if learned is not None:
            learned.open_into(session.pipeline.observe)
        _run_until_stopped(args, table)
    finally:
        if learned is not None:
            learned.close()
        if tap is not None:
            tap.close()
        session.close()
    _report_errors(session)
    return 0


__all__ = ["observe", "Update"]
