"""faultmas robot bridges: one small protocol through which agents drive robots, real or simulated.

``protocol`` (the interface), ``actions`` and ``percepts`` (the one vocabulary every bridge speaks),
``registry`` (find a bridge by name), ``sim`` (the embedded simulator, default), ``ros2`` (ROS 2 nodes),
``logging_bridge`` (the smallest example bridge). See ``robot_bridge/README.md``.
"""
from robot_bridge.protocol import Action, Completion, Percept, RobotBridge, completed
from robot_bridge.registry import (UnknownBridgeError, UnknownBridgeOptionError, available, create, create_team,
                                   load)

__all__ = ["Action", "Completion", "Percept", "RobotBridge", "completed", "UnknownBridgeError",
           "UnknownBridgeOptionError", "available", "create", "create_team", "load"]
