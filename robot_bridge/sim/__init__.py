"""The embedded simulator, the default bridge: Kobuki physics, fault injection, motion, a shared world.

Layers, each usable alone: ``kobuki`` (pure physics), ``faults`` (pure injector), ``odometry`` (the
robot's dead reckoning), ``motion`` (move/turn/rotate/stop to wheel commands), ``world`` (several robots,
one simulated clock), ``runner`` (paces a world against wall time), ``bridge`` (``SimBridge``),
``camera`` (the Kinect-like RGB-D renderer). See ``robot_bridge/README.md``.
"""
