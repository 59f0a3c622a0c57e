"""One observing run: the configuration, its observers, and the pipeline to the diagnoser and the rules.

Shared by ``faultmas observe``, the tests and the benchmark, live or over a bag.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from detection.config import ObserverConfig, load_observers
from detection.observer_set import ObserverSet
from detection.pipeline import Pipeline, Update
from diagnosis.actions import ActionEnvironment


@dataclass
class Session:
    config: ObserverConfig
    observers: ObserverSet
    pipeline: Pipeline

    def use_model(self, model, rules_path: str | Path | None = None,
                  environment: ActionEnvironment | None = None) -> None:
        """Diagnose with ``model`` from now on (an architecture discovered live, ``faultmas observe
        --learned`` without ``--model``); ``rules_path`` is checked against it. Before any listener."""
        from diagnosis.rules import load_rules
        rules = load_rules(rules_path, model) if rules_path is not None else []
        self.pipeline.close()
        self.pipeline = Pipeline(model, rules, environment)

    def close(self) -> None:
        self.pipeline.close()


def open_session(config_path: str | Path | None, model_path: str | Path | None = None,
                 rules_path: str | Path | None = None, environment: ActionEnvironment | None = None) -> Session:
    """Load everything (``SourceError`` on bad input). Without ``rules_path`` the model's neighbour
    ``NAME.rules.yaml`` is used when it exists. Without ``config_path`` there are no observers (another
    detector, e.g. the learned one, feeds the pipeline)."""
    from diagnosis.rules import load_rules, rules_path_for

    config = load_observers(config_path) if config_path is not None else ObserverConfig("<no observers>", [])
    model = None
    if model_path is not None:
        from diagnosis.loader import load_model
        model = load_model(model_path)
        if rules_path is None and rules_path_for(model_path).is_file():
            rules_path = rules_path_for(model_path)
    rules = load_rules(rules_path, model) if rules_path is not None else []
    return Session(config, config.build(), Pipeline(model, rules, environment))


def replay_bag(session: Session, bag: str | Path, detector=None) -> list[Update]:
    """Every message of the bag through the observers and the pipeline; the updates, in order.

    The clock starts where the live run that recorded the bag started (else at the first message) and
    runs to where its clock stopped (else to the last message). ``detector`` (e.g. the learned
    observer's ``BagReplay``) gets the messages on its ``topics`` and ``channels`` instead, in the same
    order, and its observations go into the same pipeline."""
    from detection.taps.bag import replay, start_time_ns, stop_time_ns

    updates: list[Update] = []
    start = start_time_ns(bag)
    last = None
    theirs = set() if detector is None else set(detector.topics) | set(detector.channels)
    for msg in replay(bag, set(session.config.topics) | (set(detector.topics) if detector is not None else set())):
        if session.observers.t0_ns is None:
            session.observers.start(start if start is not None else msg.t_ns)
        if msg.channel in theirs:
            update = session.pipeline.observe(detector.feed(msg))
            if update is not None:
                updates.append(update)
            if msg.channel not in session.config.topics:       # the detector's alone
                last = msg.t_ns
                continue
        update = session.pipeline.observe(session.observers.feed(msg))
        if update is not None:
            updates.append(update)
        last = msg.t_ns
    stop = stop_time_ns(bag)
    if last is not None:
        update = session.pipeline.observe(session.observers.advance(max(last, stop or last)))
        if update is not None:
            updates.append(update)
    return updates
