"""The two coloured cylinders a robot carries, in one place.

Everything that knows what a robot looks like to a camera (the detector, the renderer, tests) reads
these constants, so changing a marker colour or the cylinder spacing is a one-line change.
Heights are above the floor; positions are in the robot frame (x forward, y left, REP 103).
"""
from __future__ import annotations

from dataclasses import dataclass

CYLINDER_SPACING_M = 0.227      # axis-to-axis distance of the front and rear cylinders (seed paper)
CYLINDER_RADIUS_M = 0.03
CYLINDER_BOTTOM_M = 0.42        # on the TurtleBot 2 top plate
CYLINDER_TOP_M = 0.57
FRONT_OFFSET_M = CYLINDER_SPACING_M / 2     # front cylinder axis at (+0.1135, 0) in the robot frame
REAR_OFFSET_M = -CYLINDER_SPACING_M / 2

SPACING_RANGE_M = (0.20, 0.26)  # 3D axis distances accepted as one robot's pair


@dataclass(frozen=True)
class HsvRange:
    """An OpenCV HSV box (H 0-179, S and V 0-255), inclusive; lo_h > hi_h wraps through red."""

    lo: tuple[int, int, int]
    hi: tuple[int, int, int]


# Wider in V than the seed paper's orange (0,136,159)-(29,255,255) so that dim scenes (gain 0.5) pass;
# higher in S (painted markers are S > 0.85), which keeps cardboard, wood and skin (S ~ 0.4-0.6) out;
# blue from S 200 (0.78): navy things (S ~ 0.75) are not the blue marker.
# H starts at 5, not 0, so that red things (H 170-179 and 0-3) are not orange.
ORANGE_HSV = HsvRange((5, 170, 60), (24, 255, 255))
BLUE_HSV = HsvRange((98, 200, 40), (128, 255, 255))
GREEN_HSV = HsvRange((41, 81, 63), (66, 215, 255))     # the seed paper's green, for its colour scheme

FRONT_COLOUR = "orange"
REAR_COLOUR = "blue"

# Surface colours (RGB, fully lit) the simulator paints the markers with; they fall inside the ranges.
MARKER_RGB = {"orange": (255, 110, 15), "blue": (25, 70, 215), "green": (40, 190, 60)}
