"""faultmas: the ROS 2 Jazzy side of the robot bridge (rclpy from the PyPI wheels, extra ``ros2``).

Per robot namespace (``/faulty``, ``/helper``) the nodes mirror a TurtleBot 2 (Kobuki base + Kinect)
so plans and perception run unchanged against a real robot:

| node | in | out |
|---|---|---|
| ``motion_decomposer`` | ``jason/actions`` | ``commands/velocity_raw``, ``jason/actions_status`` (on completion) |
| ``fault_injector`` | ``commands/velocity_raw``, parameter ``fault`` | ``commands/velocity``, ``faults/active`` |
| ``kobuki_sim`` | ``commands/velocity`` (Twist), ``faults/active`` | ``odom``, ``sensors/core``, ``joint_states``, ``ground_truth`` |
| ``camera_sim`` | ``ground_truth`` of every robot | ``camera/rgb/image_raw``, ``camera/depth_registered/image_raw``, ``camera/rgb/camera_info`` |
| ``visual_synthesizer`` | the camera topics | ``jason/percepts`` (``robot(Name,Angle,Depth,Yaw)``) |

The agent side is :class:`robot_bridge.ros2.bridge.Ros2Bridge`. Nothing in this package imports
rclpy at import time except the node modules, so the bridge can be found without ROS installed.
"""
