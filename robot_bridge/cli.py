"""``faultmas sim ...`` (the embedded simulator) and ``faultmas ros ...`` (from ``robot_bridge.ros2.cli``).

``faultmas sim run`` drives one robot through a scripted list of actions, with a fault injected, and
prints each completion and the final ground truth next to what odometry believes; ``--csv`` and
``--plot`` save the trajectories. ``faultmas sim bridges`` lists the installed bridges.
"""
from __future__ import annotations

import argparse
import re
import sys

from robot_bridge.protocol import Action, Value

_ACTION = re.compile(r"\s*([a-z][A-Za-z0-9_]*)\s*(?:\(([^()]*)\))?\s*")


def parse_script(text: str) -> list[Action]:
    """``"move(1); turn(90); stop"`` -> actions; raises ``ValueError`` naming the column of a bad one."""
    found, pos = [], 0
    while pos < len(text.rstrip()):
        match = _ACTION.match(text, pos)
        if not match:
            raise ValueError(f"--script, column {pos + 1}: expected an action like move(0.5) or stop, "
                             f"got {text[pos:pos + 20]!r}")
        name, args = match.group(1), match.group(2)
        values = tuple(_value(a.strip(), pos) for a in args.split(",")) if args and args.strip() else ()
        found.append(Action(name, values))
        pos = match.end()
        if pos < len(text) and text[pos] != ";":
            raise ValueError(f"--script, column {pos + 1}: expected ';' between actions, "
                             f"got {text[pos:pos + 20]!r}")
        pos += 1
    return found


def _value(text: str, pos: int) -> Value:
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        pass
    if re.fullmatch(r"[a-z][A-Za-z0-9_]*", text):
        return text
    raise ValueError(f"--script, near column {pos + 1}: {text!r} is neither a number nor an atom")


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``faultmas sim`` and, when its module is there, ``faultmas ros``."""
    try:
        from robot_bridge.ros2.cli import add_ros_parser
    except ModuleNotFoundError as exc:
        if exc.name != "robot_bridge.ros2.cli":
            raise
    else:
        add_ros_parser(subparsers)

    sim = subparsers.add_parser("sim", help="the embedded simulator: scripted runs with faults")
    sim_sub = sim.add_subparsers(dest="sim_command", metavar="SIM_COMMAND")
    sim.set_defaults(func=lambda args: (sim.print_help(), 2)[1])

    run = sim_sub.add_parser("run", help="drive a robot through a script of actions, with a fault",
                             description="Drive the first robot through a script of actions on the embedded "
                                         "simulator, with a fault injected, and show what its sensors reported.")
    run.add_argument("--script", default="move(1.0); turn(90); move(0.5)",
                     help="actions for the first robot, separated by ';' (default: %(default)s)")
    run.add_argument("--robots", default="faulty,helper",
                     help="comma-separated robot names (default: %(default)s)")
    run.add_argument("--fault", default="none",
                     help="fault of the first robot: none, encoders, both_actuators, left_actuator[:FRACTION], "
                          "right_actuator[:FRACTION], stuck_wheels (default: %(default)s)")
    run.add_argument("--seed", type=int, default=0, help="seed of the simulator's noise (default %(default)s)")
    run.add_argument("--csv", metavar="PATH", help="write every robot's trajectory (truth and odometry) as CSV")
    run.add_argument("--plot", metavar="PATH", help="plot the trajectories to an image (e.g. run.png)")
    run.set_defaults(func=run_script)

    bridges = sim_sub.add_parser("bridges", help="list the robot bridges installed (entry-point group)")
    bridges.set_defaults(func=list_bridges)

    serve = sim_sub.add_parser(
        "serve", help="serve a simulated world over Zenoh to agents started by hand with --bridge zenoh",
        description="Serve the robots of one simulated world over Zenoh (robot_bridge.sim.server), side by side "
                    "1.5 m apart, all facing +x, each with a camera, until Ctrl-C or --timeout. Agents started by "
                    "hand drive them: `faultmas agent run PLAN.asl --name ROBOT --mas MAS --connect ENDPOINT "
                    "--bridge zenoh` (docs/bridges.md).")
    serve.add_argument("--mas", required=True, help="the MAS the agents join (the robots' key prefix)")
    serve.add_argument("--robots", default="faulty,helper",
                       help="comma-separated robot names, one per agent (default: %(default)s)")
    serve.add_argument("--fault", action="append", default=[], metavar="ROBOT=KIND",
                       help="inject fault KIND (e.g. encoders, left_actuator:0.5) into ROBOT (repeatable)")
    serve.add_argument("--listen", action="append", default=None, metavar="ENDPOINT",
                       help="endpoint the agents connect to (repeatable; default tcp/127.0.0.1:7447)")
    serve.add_argument("--connect", action="append", default=[], metavar="ENDPOINT",
                       help="also connect to this peer or router (repeatable)")
    serve.add_argument("--seed", type=int, default=0, help="seed of the simulator's noise (default %(default)s)")
    serve.add_argument("--speed", type=float, default=0.0,
                       help="simulated seconds per wall second; 0: as fast as possible while anything moves "
                            "(default %(default)s)")
    serve.add_argument("--timeout", type=float, default=None, metavar="S",
                       help="stop after S seconds (default: run until interrupted)")
    serve.add_argument("--project", default=None, metavar="PROJECT.mas2j",
                       help="a project in the secure profile (key= options): sign what the robots send as its "
                            "environment and take only actions signed by each robot's agent")
    serve.add_argument("--identity", default=None, metavar="KEY.pem",
                       help="with --project: the environment's private key (default: the .key beside the public "
                            "key its environment line names)")
    serve.set_defaults(func=serve_world)


DEFAULT_SERVE_LISTEN = "tcp/127.0.0.1:7447"


def serve_world(args: argparse.Namespace) -> int:
    """``faultmas sim serve``: one world, its robots served over Zenoh until SIGINT/SIGTERM or ``--timeout``."""
    import signal
    import threading

    from robot_bridge.sim.faults import Fault

    names = [n.strip() for n in args.robots.split(",") if n.strip()]
    faults: dict[str, str] = {}
    try:
        if not names or len(set(names)) != len(names):
            raise ValueError(f"--robots needs distinct names, got {args.robots!r}")
        for text in args.fault:
            robot, sep, kind = text.partition("=")
            if not sep or robot.strip() not in names:
                raise ValueError(f"--fault expects ROBOT=KIND with ROBOT among {', '.join(names)}, got {text!r}")
            Fault.parse(kind.strip())
            faults[robot.strip()] = kind.strip()
        if args.speed < 0:
            raise ValueError(f"--speed must be >= 0, got {args.speed:g}")
        sealed = _environment_seal(args)
    except OSError as exc:
        print(f"faultmas sim serve: cannot read {exc.filename}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except ValueError as exc:   # IdentityError, a project's located error too
        print(f"faultmas sim serve: {exc}", file=sys.stderr)
        return 2
    import zenoh

    from agents.router import start_failure
    from agents.transport.config import ZenohOptions, build_config, listen_endpoints
    from robot_bridge.sim.bridge import SimBridge
    from robot_bridge.sim.server import SimServer

    config = build_config(ZenohOptions(listen=tuple(args.listen or (DEFAULT_SERVE_LISTEN,)),
                                       connect=tuple(args.connect)))
    try:
        session = zenoh.open(config)
    except zenoh.ZError as exc:
        print(f"faultmas sim serve: {start_failure(listen_endpoints(config), str(exc))}", file=sys.stderr)
        return 1
    bridges = SimBridge.for_team(names, seed=args.seed, speed=args.speed, camera=True)
    world = next(iter(bridges.values())).world
    for name, bridge in bridges.items():
        bridge.setup()
        world.set_fault(name, faults.get(name, "none"))
    server = SimServer(session, args.mas, bridges, sealed=sealed).start()
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())
    endpoint = listen_endpoints(config)[0]
    robots = ", ".join(f"{name} (fault {faults.get(name, 'none')})" for name in names)
    print(f"faultmas sim serve: robots {robots} of MAS {args.mas} on {endpoint}; drive one with: faultmas agent "
          f"run PLAN.asl --name ROBOT --mas {args.mas} --connect {endpoint} --bridge zenoh", flush=True)
    try:
        stop.wait(args.timeout)
    finally:
        server.stop()
        for bridge in bridges.values():
            bridge.shutdown()
        session.close()
    for name in names:   # where each robot ended, and what it believes: the run's outcome at a glance
        x, y, yaw = world.pose(name)
        odom = world.odometry(name)
        print(f"{name}: truth ({x:.3f}, {y:.3f}, {yaw:.1f} deg)  odometry ({odom.x:.3f}, {odom.y:.3f})")
    print(f"faultmas sim serve: {server.requests} action requests served")
    return 0


def _environment_seal(args: argparse.Namespace):
    """The secure profile of ``--project`` for the process that serves its robots (None: the default profile):
    the environment's key signs, the drops go to a rate-limited log (``agents.transport.drop_log``)."""
    if args.project is None:
        if args.identity is not None:
            raise ValueError("--identity needs --project (the project lists the keys)")
        return None
    import logging

    from agents.transport.drop_log import DropLog
    from agents.transport.identity import ENVIRONMENT, project_identity
    from agents.transport.sealed import SealedChannel
    from agentspeak.mas2j import load_mas2j

    project = load_mas2j(args.project)
    if args.mas != project.name:
        raise ValueError(f"--mas {args.mas} but {args.project} is MAS {project.name}")
    identity = project_identity(project, [ENVIRONMENT], args.identity)
    if identity is None:
        raise ValueError(f"{args.project} lists no keys (key= options): it is not in the secure profile")
    return SealedChannel(identity, DropLog(logging.getLogger("faultmas.sim")).drop)


def list_bridges(args: argparse.Namespace) -> int:
    from robot_bridge.registry import GROUP, available
    print(f"{GROUP}: {', '.join(available()) or 'none'}")
    return 0


def run_script(args: argparse.Namespace) -> int:
    from robot_bridge.sim.bridge import SimBridge
    from robot_bridge.sim.faults import Fault
    from robot_bridge.sim.world import World

    try:
        script = parse_script(args.script)
        fault = Fault.parse(args.fault)
    except ValueError as exc:
        print(f"faultmas sim run: {exc}", file=sys.stderr)
        return 2
    names = [n.strip() for n in args.robots.split(",") if n.strip()]
    if not names or len(set(names)) != len(names):
        print(f"faultmas sim run: --robots needs distinct names, got {args.robots!r}", file=sys.stderr)
        return 2
    world = World(seed=args.seed, log_keep=None)       # --csv and --plot show the whole run
    for i, name in enumerate(names):
        world.add_robot(name, x=1.5 * i, y=0.0, yaw_deg=0.0 if i == 0 else 180.0,
                        fault=fault if i == 0 else "none")
    bridge = SimBridge(names[0], world=world, drive=False)   # the script steps the clock: deterministic
    bridge.setup()
    failed = 0
    for action in script:
        future = bridge.act(action)
        world.run_until(future.done, 600.0)
        result = future.result() if future.done() else None
        outcome = "ok" if result and result.ok else f"FAILED {result.reason if result else 'still running'}"
        detail = f" ({result.detail})" if result and result.detail else ""
        print(f"t={world.time:7.2f} s  {str(action):<24} {outcome}{detail}")
        failed += not (result and result.ok)
    world.run_until_idle(5.0)
    bridge.shutdown()
    for name in names:
        x, y, yaw = world.pose(name)
        odom = world.odometry(name)
        print(f"{name}: truth ({x:.3f}, {y:.3f}, {yaw:.1f} deg)  odometry ({odom.x:.3f}, {odom.y:.3f}, "
              f"{odom.yaw * 57.29577951308232:.1f} deg)  fault {world.fault(name).kind}")
    if args.csv:
        write_csv(world, args.csv)
    if args.plot:
        plot(world, args.plot)
    return 1 if failed else 0


def write_csv(world, path: str) -> None:
    """One row per robot and logged instant: ground truth next to odometry."""
    import csv

    with open(path, "w", newline="") as out:
        writer = csv.writer(out)
        writer.writerow(("robot", "time", "x", "y", "yaw_deg", "odom_x", "odom_y", "odom_yaw_deg"))
        for name in world.robots:
            for point in world.trajectory(name):
                writer.writerow((name, *(f"{v:.4f}" for v in point)))


def plot(world, path: str, title: str | None = None) -> None:
    """Ground truth (solid) and odometry (dashed, drawn on top so that it shows where the two agree) of every
    robot, to an image file; the legend beside the axes, never over the data."""
    import math

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.5, 6))
    for name in world.robots:
        log = world.trajectory(name)
        line, = ax.plot([p.x for p in log], [p.y for p in log], linewidth=4, alpha=0.45, label=f"{name} truth")
        x0, y0, yaw0 = log[0].x, log[0].y, math.radians(log[0].yaw_deg)
        c, s = math.cos(yaw0), math.sin(yaw0)
        ax.plot([x0 + c * p.odom_x - s * p.odom_y for p in log], [y0 + s * p.odom_x + c * p.odom_y for p in log],
                "--", linewidth=1.5, color=line.get_color(), zorder=3,
                label=f"{name} odometry (from its start)")
        ax.plot([x0], [y0], "o", color=line.get_color(), zorder=4)
        ax.plot([log[-1].x], [log[-1].y], "s", color=line.get_color(), zorder=4)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    if title:
        ax.set_title(title, fontsize="medium")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize="small", borderaxespad=0.0,
              title="o start, \u25a0 end", title_fontsize="small")
    fig.savefig(path, dpi=100, bbox_inches="tight")
    plt.close(fig)
