"""An outsider process against a ``faultmas run --secure`` team (tests/hardening/test_run_secure_outsider.py).

It knows what anyone on the host can read (the MAS name and the hub's endpoint from the agents' command
lines, the envelope and control formats) and has a key pair of its own (``--key``, not in the project). Once
the robots are up it tries, each as a separate network message, against every robot: an unsigned tell, an
unsigned goal under another member's name, its own signed tell/achieve/tellHow/askOne, a tell under another
member's name signed with its own key; on the control key: stops (unsigned under a member's name, signed by
itself, claiming to be the launcher) and forged ``.progress`` reports that would end the run with a wrong
diagnosis (unsigned under the faulty robot's name, signed by itself, and under the faulty robot's name
signed with its own key). On the robots' keys: percepts (unsigned, signed with its own key, another robot's
put again) and a clock far ahead, actions the agents never asked for, and a failure answering the faulty robot's
first action before its robot does. For the run's inspector: a forged mind of the faulty robot, and a pause and a
step of it. For the directory: the helper's subscription to a service it never subscribed to (its token, and
queries saying so), and a token of its own. Prints ``READY`` once connected and ``SENT`` when done."""
from __future__ import annotations

import argparse
import json
import sys
import time

from agents.transport import ZenohOptions, ZenohTransport
from agents.transport.identity import load_private_key
from agents.transport.keys import inbox_key
from tests.hardening.outsider_attacks import (StatusForger, attack_inbox, attack_stop, forge_actions, forge_minds,
                                             forge_pause, forge_percepts, forge_progress, claim_subscriptions,
                                             forge_subscription_queries)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--mas", required=True)
    parser.add_argument("--connect", required=True)
    parser.add_argument("--key", required=True, help="the outsider's own private key (PEM)")
    parser.add_argument("--robots", required=True, help="the robots' agent names, comma-separated")
    parser.add_argument("--faulty", required=True, help="the faulty robot, whose diagnosis is forged")
    parser.add_argument("--wrong", required=True, help="the wrong diagnosis the forged reports claim")
    args = parser.parse_args()
    mas, robots = args.mas, args.robots.split(",")
    own_key = load_private_key(args.key)

    with ZenohTransport(mas, ZenohOptions(mode="client", connect=(args.connect,))) as transport:
        session = transport.session
        status_forger = StatusForger(session, mas, args.faulty, own_key)   # before the faulty robot's first action
        minds = forge_minds(session, mas, args.faulty, own_key)             # for the run's inspector
        helper = next(r for r in robots if r != args.faulty)
        tokens = claim_subscriptions(session, mas, helper, "evil_service")    # seen as the robots start
        print("READY", flush=True)
        assert transport.wait_for_agents(robots, timeout=120), "the robots never appeared"
        print("robots up", file=sys.stderr, flush=True)
        forge_percepts(session, mas, args.faulty, helper, own_key)
        answers = forge_pause(session, mas, args.faulty, own_key)
        assert answers and not any(json.loads(answer)["ok"] for answer in answers), answers   # not held
        forge_subscription_queries(session, mas, helper, "evil_service", own_key)
        forge_actions(session, mas, robots, own_key)
        print("robots' keys, inspector and directory forged", file=sys.stderr, flush=True)
        assert status_forger.done.wait(60), "the faulty robot's agent never asked for an action"
        for robot in robots:
            other = next(r for r in robots if r != robot)
            attack_inbox(lambda payload, robot=robot: session.put(inbox_key(mas, robot), payload), mas, robot,
                         other, own_key, goal="evil_goal", query="destination(X)")
        attack_stop(transport, mas, robots[0], own_key)
        forge_progress(transport, mas, args.faulty, "diagnosed", args.wrong, own_key)
        time.sleep(0.5)  # let the puts leave before the session closes
        del minds, tokens
    print("SENT", flush=True)


if __name__ == "__main__":
    main()
