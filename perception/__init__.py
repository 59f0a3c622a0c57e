"""faultmas perception: find a robot by its two coloured cylinders in an RGB-D frame.

* ``perception.camera``   - ``CameraModel`` (pinhole, optical frame: x right, y down, z forward)
* ``perception.markers``  - the cylinders' geometry and colours, in one place
* ``perception.detect``   - ``detect`` / ``detect_all`` -> ``DetectionResult`` (bearing, depth, heading)
* ``perception.tracking`` - ``Tracker``: smoothing, and "lost" only after N missed frames
* ``perception.cli``      - ``faultmas perceive --rgb IMG.png --depth DEPTH.npy [--json]``

Nothing is imported here, so ``from perception import markers`` stays cheap.
"""
