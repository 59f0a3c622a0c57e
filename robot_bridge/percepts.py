"""THE percept vocabulary: every percept any bridge delivers, in one place, with units.

The agent architecture turns each ``Percept`` into an AgentSpeak literal annotated ``source(percept)``,
e.g. ``odom(1.2,0.05,90.0)[source(percept)]``. Plans are written against this list only, so they never
know which bridge they run on. Build percepts with the functions below (they round values, so that an
agent diffing successive snapshots is not flooded by sensor jitter). Units: metres, degrees, seconds;
angles counter-clockwise (left) positive, yaw in (-180, 180].

=================================== ===================================================================
percept                             meaning
=================================== ===================================================================
``odom(X, Y, YawDeg)``              the pose the robot *believes* it has, from its own wheel odometry
                                    (m, m, deg; origin = where it started or last ``reset_odometry``)
``encoders(LeftTicks, RightTicks)`` raw wheel encoder counters (uint16, wrap at 65536; 2578.33 ticks per
                                    wheel revolution on a Kobuki)
``moving`` / ``stopped``            whether odometry shows the base in motion (a belief: with dead
                                    encoders a driving robot perceives ``stopped``)
``bumper(Side)``                    a front bumper is pressed; Side is ``left``, ``centre`` or ``right``
``over_current(Wheel)``             a wheel motor is overloaded (pushing a blocked wheel); ``left``/``right``
``camera_ok``                       the camera delivers frames
``camera_failed(Part)``             the camera's frames arrive but ``Part`` of its pipeline (``detector``) has
                                    failed on the last ``CAMERA_FAILED_AFTER`` (10) frames in a row: no
                                    ``robot_seen`` until it works again; replaces ``camera_ok`` meanwhile
``robot_seen(Name, AngleDeg,        the camera sees robot ``Name`` (the seed paper's
DepthM, YawDeg)``                   ``robot(Name,Angle,Depth,Yaw)``): bearing from the optical axis, left
                                    positive (so ``turn(AngleDeg)`` faces it; the paper's formula has the
                                    opposite sign), depth to its markers (m), and its heading relative to
                                    the observer's (0 = same direction, 180 = facing the observer)
=================================== ===================================================================
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from robot_bridge.protocol import Percept


@dataclass(frozen=True)
class PerceptSpec:
    """One entry of the vocabulary: name, argument names (with units) and meaning."""

    name: str
    args: tuple[str, ...]
    doc: str


VOCABULARY: dict[tuple[str, int], PerceptSpec] = {(s.name, len(s.args)): s for s in (
    PerceptSpec("odom", ("X m", "Y m", "YawDeg deg"), "believed pose from the robot's own odometry"),
    PerceptSpec("encoders", ("LeftTicks", "RightTicks"), "raw uint16 wheel encoder counters"),
    PerceptSpec("moving", (), "odometry shows the base in motion"),
    PerceptSpec("stopped", (), "odometry shows the base at rest"),
    PerceptSpec("bumper", ("Side left|centre|right",), "a front bumper is pressed"),
    PerceptSpec("over_current", ("Wheel left|right",), "a wheel motor is overloaded"),
    PerceptSpec("camera_ok", (), "the camera delivers frames"),
    PerceptSpec("camera_failed", ("Part",), "a part of the camera's pipeline fails on every frame"),
    PerceptSpec("robot_seen", ("Name", "AngleDeg deg", "DepthM m", "YawDeg deg"),
                "another robot seen by the camera"),
)}


CAMERA_FAILED_AFTER = 10
"""A camera's pipeline that has failed on this many frames in a row (a second at 10 Hz) is reported as
``camera_failed(Part)`` (instead of ``camera_ok``) until it handles a frame again, by every bridge: one bad frame
is dropped and logged, a pipeline that keeps failing is a fault the robot perceives, as a real robot's diagnostics
report a camera driver or perception node that stopped working, instead of the robot silently seeing nothing."""


def normalize_degrees(angle: float) -> float:
    """``angle`` (deg) brought into (-180, 180]."""
    wrapped = math.fmod(angle, 360.0)
    if wrapped <= -180.0:
        wrapped += 360.0
    elif wrapped > 180.0:
        wrapped -= 360.0
    return wrapped


def odom(x: float, y: float, yaw_deg: float) -> Percept:
    """``odom(X, Y, YawDeg)``: believed pose, rounded to 1 mm and 0.1 degree."""
    return Percept("odom", (round(float(x), 3), round(float(y), 3), round(normalize_degrees(float(yaw_deg)), 1)))


def encoders(left_ticks: int, right_ticks: int) -> Percept:
    """``encoders(LeftTicks, RightTicks)``: raw uint16 counters."""
    return Percept("encoders", (int(left_ticks) & 0xFFFF, int(right_ticks) & 0xFFFF))


def motion_state(moving: bool) -> Percept:
    """``moving`` or ``stopped``."""
    return Percept("moving" if moving else "stopped")


def bumper(side: str) -> Percept:
    """``bumper(Side)`` with Side in left, centre, right."""
    if side not in ("left", "centre", "right"):
        raise ValueError(f"bumper side must be left, centre or right, got {side!r}")
    return Percept("bumper", (side,))


def over_current(wheel: str) -> Percept:
    """``over_current(Wheel)`` with Wheel in left, right."""
    if wheel not in ("left", "right"):
        raise ValueError(f"wheel must be left or right, got {wheel!r}")
    return Percept("over_current", (wheel,))


def camera_ok() -> Percept:
    """``camera_ok``."""
    return Percept("camera_ok")


def camera_failed(part: str) -> Percept:
    """``camera_failed(Part)``: ``part`` (e.g. ``detector``) of the camera's pipeline keeps failing."""
    return Percept("camera_failed", (str(part),))


def robot_seen(name: str, angle_deg: float, depth_m: float, yaw_deg: float) -> Percept:
    """``robot_seen(Name, AngleDeg, DepthM, YawDeg)``, rounded to 1 degree and 1 cm as the paper did."""
    return Percept("robot_seen", (name, float(round(angle_deg)), round(depth_m, 2),
                                  float(round(normalize_degrees(yaw_deg)))))


def validate(percept: Percept) -> None:
    """Raise ``ValueError`` if ``percept`` is not in the vocabulary (bridges' tests call this)."""
    if (percept.name, len(percept.args)) not in VOCABULARY:
        known = ", ".join(f"{n}/{a}" for n, a in VOCABULARY)
        raise ValueError(f"percept {literal(percept)} is not in the vocabulary ({known})")


def literal(percept: Percept) -> str:
    """AgentSpeak text of ``percept`` without annotations, e.g. ``odom(1.2,0.0,90.0)``."""
    if not percept.args:
        return percept.name
    return f"{percept.name}({','.join(_term(a) for a in percept.args)})"


def _term(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, tuple):
        return f"[{','.join(_term(v) for v in value)}]"
    return str(value)
