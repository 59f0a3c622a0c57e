"""Seed-driven random camera scenes: one observed robot in a room with clutter, occluders and lighting.

Tests and the perception benchmark draw scenes from here so that every scene can be re-created from
its seed, and ground truth always comes from the renderer's geometry (``camera.true_view``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from perception import markers
from robot_bridge.sim.camera import BoxProp, CameraRig, CylinderProp, Pose, Scene, Wall

WALL_COLOURS = ((205, 200, 188), (228, 228, 224), (180, 182, 186), (196, 210, 190), (172, 186, 210),
                (214, 196, 170))
FLOOR_COLOURS = ((150, 140, 128), (120, 120, 122), (150, 122, 94), (96, 100, 108), (176, 168, 150))
# clutter: greys, wood, cardboard (orange-ish hue, medium saturation), red, yellow, green, navy
PROP_COLOURS = ((90, 90, 92), (200, 200, 196), (40, 40, 44), (150, 112, 74), (160, 118, 70), (200, 30, 35),
                (230, 200, 40), (60, 150, 70), (30, 40, 120), (110, 70, 60), (240, 150, 150))


@dataclass(frozen=True)
class SceneSample:
    """A camera looking at ``robots[0]`` (the target) in ``scene``; re-creatable from ``seed``."""

    seed: int
    rig: CameraRig
    camera_pose: Pose                   # pose of the optical centre (world frame)
    robots: tuple[Pose, ...]
    scene: Scene
    occluder: bool = False              # an occluder was put on the line of sight
    notes: tuple[str, ...] = field(default=())


def random_scene(seed: int, *, rig: CameraRig | None = None, distance_m: tuple[float, float] = (0.8, 4.0),
                 bearing_deg: tuple[float, float] = (-27.0, 27.0), gain: tuple[float, float] = (0.5, 1.5),
                 clutter: int = 6, occlusion: float = 0.3, orange_distractor: float = 0.3,
                 second_robot: float = 0.1) -> SceneSample:
    """A random scene: target depth and bearing uniform in the given ranges, any heading.

    ``clutter`` is the largest number of props; ``occlusion``, ``orange_distractor`` and
    ``second_robot`` are probabilities of an occluder on the line of sight, a lone marker-sized orange
    cylinder, and a second robot in view.
    """
    rng = np.random.default_rng(seed)
    rig = rig or CameraRig()
    cam_pose: Pose = (float(rng.uniform(-2, 2)), float(rng.uniform(-2, 2)), float(rng.uniform(-math.pi, math.pi)))
    cx, cy, cyaw = cam_pose
    f = (math.cos(cyaw), math.sin(cyaw))
    rgt = (math.sin(cyaw), -math.cos(cyaw))

    def world(x_right: float, z_fwd: float) -> tuple[float, float]:
        return (cx + z_fwd * f[0] + x_right * rgt[0], cy + z_fwd * f[1] + x_right * rgt[1])

    z = float(rng.uniform(*distance_m))
    b = math.radians(float(rng.uniform(*bearing_deg)))
    tx, ty = world(z * math.tan(b), z)
    robots: list[Pose] = [(tx, ty, float(rng.uniform(-math.pi, math.pi)))]
    notes: list[str] = []
    if rng.random() < second_robot:
        for _ in range(20):
            z2, b2 = float(rng.uniform(1.0, 4.5)), math.radians(float(rng.uniform(-30, 30)))
            x2, y2 = world(z2 * math.tan(b2), z2)
            if math.hypot(x2 - tx, y2 - ty) > 0.6:
                robots.append((x2, y2, float(rng.uniform(-math.pi, math.pi))))
                notes.append("second_robot")
                break

    walls = _room(rng, world, z)
    props: list[CylinderProp | BoxProp] = []

    def free(x: float, y: float, clearance: float) -> bool:
        """Clear of the robots and the camera, and not on the line of sight to the target."""
        return (all(math.hypot(x - rx, y - ry) > clearance + 0.2 for rx, ry, _ in robots)
                and math.hypot(x - cx, y - cy) > clearance + 0.3
                and _segment_distance(x, y, cx, cy, tx, ty) > clearance + 0.3)

    for _ in range(int(rng.integers(0, clutter + 1))):
        for _ in range(10):
            pz, pb = float(rng.uniform(0.7, 6.0)), math.radians(float(rng.uniform(-35, 35)))
            px, py = world(pz * math.tan(pb), pz)
            rgb = PROP_COLOURS[int(rng.integers(len(PROP_COLOURS)))]
            if rng.random() < 0.5:
                rad = float(rng.uniform(0.03, 0.25))
                if free(px, py, rad):
                    bottom = float(rng.choice([0.0, 0.0, rng.uniform(0.2, 0.8)]))
                    props.append(CylinderProp(px, py, rad, bottom, bottom + float(rng.uniform(0.1, 1.4)), rgb))
                    break
            else:
                ln, wd = float(rng.uniform(0.1, 0.8)), float(rng.uniform(0.1, 0.6))
                if free(px, py, math.hypot(ln, wd) / 2):
                    props.append(BoxProp(px, py, float(rng.uniform(-math.pi, math.pi)), ln, wd, 0.0,
                                         float(rng.uniform(0.1, 1.2)), rgb))
                    break
    if rng.random() < orange_distractor:
        for _ in range(20):
            pz, pb = float(rng.uniform(0.8, 4.5)), math.radians(float(rng.uniform(-28, 28)))
            px, py = world(pz * math.tan(pb), pz)
            if free(px, py, 0.3):
                bottom = float(rng.uniform(0.0, 0.9))
                colour = markers.FRONT_COLOUR if rng.random() < 0.7 else markers.REAR_COLOUR
                props.append(CylinderProp(px, py, markers.CYLINDER_RADIUS_M, bottom,
                                          bottom + markers.CYLINDER_TOP_M - markers.CYLINDER_BOTTOM_M,
                                          markers.MARKER_RGB[colour]))
                notes.append(f"lone_{colour}")
                break
    occluded = False
    if rng.random() < occlusion:
        props.append(_occluder(rng, rig, cam_pose, robots[0], z))
        occluded = True
        notes.append("occluder")
    scene = Scene(walls=walls, props=tuple(props), gain=float(rng.uniform(*gain)),
                  floor_rgb=FLOOR_COLOURS[int(rng.integers(len(FLOOR_COLOURS)))])
    return SceneSample(seed, rig, cam_pose, tuple(robots), scene, occluded, tuple(notes))


def _room(rng: np.random.Generator, world, target_z: float) -> tuple[Wall, ...]:
    """Four walls around the camera, the far one somewhere behind the target robot (often out of range)."""
    far = target_z + float(rng.uniform(0.45, 4.0))
    left, right = float(rng.uniform(1.8, 4.5)), float(rng.uniform(1.8, 4.5))
    back = float(rng.uniform(0.5, 3.0))
    corners = [world(-left, far), world(right, far), world(right, -back), world(-left, -back)]
    colour = WALL_COLOURS[int(rng.integers(len(WALL_COLOURS)))]
    height = float(rng.uniform(1.0, 2.6))
    walls = []
    for i in range(4):
        (x0, y0), (x1, y1) = corners[i], corners[(i + 1) % 4]
        walls.append(Wall(x0, y0, x1, y1, height, colour))
    return tuple(walls)


def _occluder(rng: np.random.Generator, rig: CameraRig, cam_pose: Pose, robot: Pose,
              z: float) -> CylinderProp | BoxProp:
    """A pole or box part-way along the line of sight to one of the target's markers."""
    cx, cy, _ = cam_pose
    rx, ry, ryaw = robot
    off = markers.FRONT_OFFSET_M if rng.random() < 0.5 else markers.REAR_OFFSET_M
    mx, my = rx + math.cos(ryaw) * off, ry + math.sin(ryaw) * off
    frac = float(rng.uniform(0.3, 0.75))
    if z * (1 - frac) < 0.35:                 # keep clear of the robot body
        frac = max(0.1, 1 - 0.35 / z)
    px, py = cx + frac * (mx - cx), cy + frac * (my - cy)
    dx, dy = mx - cx, my - cy
    n = math.hypot(dx, dy)
    side = (-dy / n, dx / n)
    # thin enough near the camera not to hide both cylinders; its edge falls on the chosen marker
    rad = float(rng.uniform(0.01, max(0.012, min(0.05, 0.06 * frac))))
    shift = (1 if rng.random() < 0.5 else -1) * (rad + float(rng.uniform(-1.0, 1.0)) * markers.CYLINDER_RADIUS_M * frac)
    px, py = px + side[0] * shift, py + side[1] * shift
    rgb = PROP_COLOURS[int(rng.integers(len(PROP_COLOURS)))]
    if rng.random() < 0.7:
        return CylinderProp(px, py, rad, 0.0, float(rng.uniform(0.45, 2.0)), rgb)
    return BoxProp(px, py, float(rng.uniform(-math.pi, math.pi)), 2 * rad, float(rng.uniform(0.03, 0.12)),
                   float(rng.uniform(0.0, 0.5)), float(rng.uniform(0.6, 1.5)), rgb)


def _segment_distance(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    """Distance from point p to segment a-b."""
    ex, ey = bx - ax, by - ay
    t = max(0.0, min(1.0, ((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey)))
    return math.hypot(px - ax - t * ex, py - ay - t * ey)
