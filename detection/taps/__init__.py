"""Taps: I/O only. Each turns one source of messages into ``Message`` s for an ``ObserverSet``:
``ros2`` (rclpy raw subscriptions, the graph, psutil), ``zenoh`` (key expressions, liveliness),
``bag`` (rosbag2 MCAP or sqlite3 replay and recording, through ``rosbags``)."""
