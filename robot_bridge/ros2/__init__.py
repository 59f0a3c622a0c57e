"""faultmas: the ROS 2 Jazzy side of the robot bridge (rclpy from the PyPI wheels, extra ``ros2``).

Per robot namespace (``/faulty``, ``/helper``) the nodes mirror a TurtleBot 2 (Kobuki base + Kinect),
so plans and perception run unchanged against a real robot (then only ``motion_decomposer`` and
``visual_synthesizer`` run, next to the real drivers):

======================  ==========================================  ===============================================
node                    in                                          out
======================  ==========================================  ===============================================
``motion_decomposer``   ``jason/actions``, ``sensors/core``         ``commands/velocity_raw``, ``commands/reset_odometry``,
                                                                    ``jason/actions_status`` (on completion),
                                                                    ``jason/percepts`` (source ``base``)
``fault_injector``      ``commands/velocity_raw``, param ``fault``  ``commands/velocity``, ``faults/active`` (latched)
``kobuki_sim``          ``commands/velocity``, ``faults/active``,   ``odom``, ``sensors/core``, ``joint_states``,
                        ``commands/reset_odometry``                 ``ground_truth``
``camera_sim``          ``ground_truth`` of every robot             ``camera/rgb/image_raw`` (rgb8),
                                                                    ``camera/depth_registered/image_raw`` (16UC1 mm),
                                                                    ``camera/{rgb,depth_registered}/camera_info``
``visual_synthesizer``  the camera topics                           ``jason/percepts`` (source ``camera``:
                                                                    ``camera_ok``, ``robot_seen(...)``)
======================  ==========================================  ===============================================

Run one with ``python -m robot_bridge.ros2.<node> --robot R [--domain-id N] [--ros-args -p k:=v]``,
or all of a team with ``faultmas ros launch``. The agent side is
:class:`robot_bridge.ros2.bridge.Ros2Bridge`; the wire format is in :mod:`robot_bridge.ros2.wire`.
Only the node modules import rclpy at import time, so the bridge is found and built without ROS.
"""
