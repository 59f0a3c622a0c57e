"""A ROS 2 node for the observer tests, run in its own process: ``python publisher_node.py --domain-id N ...``.

``--pub TOPIC:RATE[:MEAN]`` publishes ``std_msgs/Float64`` at RATE Hz (data ~ N(MEAN, 1), seeded) or,
with ``--stamped``, ``std_msgs/Header`` stamped now. ``--image TOPIC:RATE`` publishes a 640x480 rgb8
``sensor_msgs/Image`` (``image_message()``: the same every time) at RATE Hz. The node's ``rate`` parameter (first topic) can be
set through ROS 2; each change prints ``rate=<value>``. ``--slow-to R --slow-after S`` drops the rate
of the first topic to R after S seconds. Prints ``ready`` once publishing; SIGINT/SIGTERM end it cleanly.
"""
from __future__ import annotations

import argparse
import random
import signal
import sys
import time


def image_message():
    """The image ``--image`` publishes (a test rebuilds it to know what was sent)."""
    from sensor_msgs.msg import Image

    image = Image(height=480, width=640, encoding="rgb8", is_bigendian=0, step=1920, data=bytes(range(256)) * 3600)
    image.header.frame_id = "camera_rgb_optical_frame"
    return image


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--domain-id", type=int, required=True)
    ap.add_argument("--name", default="test_publisher")
    ap.add_argument("--pub", action="append", default=[])
    ap.add_argument("--stamped", action="store_true")
    ap.add_argument("--image", action="append", default=[])
    ap.add_argument("--slow-to", type=float, default=None)
    ap.add_argument("--slow-after", type=float, default=None)
    args = ap.parse_args()

    import rclpy
    from rcl_interfaces.msg import SetParametersResult
    from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
    from rclpy.node import Node
    from std_msgs.msg import Float64, Header

    rclpy.init(domain_id=args.domain_id)
    node = Node(args.name)
    rng = random.Random(1)
    specs = []
    for spec in args.pub:
        parts = spec.split(":")
        specs.append((parts[0], float(parts[1]), float(parts[2]) if len(parts) > 2 else 0.0))
    node.declare_parameter("rate", specs[0][1])
    timers = {}

    def publisher_for(topic, mean):
        if args.stamped:
            pub = node.create_publisher(Header, topic, 10)
            return lambda: pub.publish(Header(stamp=node.get_clock().now().to_msg(), frame_id="test"))
        pub = node.create_publisher(Float64, topic, 10)
        return lambda: pub.publish(Float64(data=rng.gauss(mean, 1.0)))

    callbacks = [publisher_for(topic, mean) for topic, _rate, mean in specs]

    def set_rate(i, rate):
        if i in timers:
            node.destroy_timer(timers[i])
        timers[i] = node.create_timer(1.0 / rate, callbacks[i])

    for i, (_topic, rate, _mean) in enumerate(specs):
        set_rate(i, rate)
    if args.image:
        from sensor_msgs.msg import Image
        image = image_message()
        for spec in args.image:
            topic, rate = spec.split(":")
            image_pub = node.create_publisher(Image, topic, 2)
            node.create_timer(1.0 / float(rate), lambda pub=image_pub: pub.publish(image))

    def on_parameters(params):
        for p in params:
            if p.name == "rate":
                set_rate(0, float(p.value))
                print(f"rate={float(p.value)}", flush=True)
        return SetParametersResult(successful=True)
    node.add_on_set_parameters_callback(on_parameters)

    if args.slow_to is not None:
        started = time.monotonic()

        def maybe_slow():
            if time.monotonic() - started >= args.slow_after:
                node.destroy_timer(slow_timer)
                node.set_parameters([rclpy.parameter.Parameter("rate", value=args.slow_to)])
        slow_timer = node.create_timer(0.05, maybe_slow)

    signal.signal(signal.SIGTERM, lambda *_: rclpy.try_shutdown())
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    print("ready", flush=True)
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
