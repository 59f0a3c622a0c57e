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
    world = World(seed=args.seed)
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
