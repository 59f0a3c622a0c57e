"""Wienke & Wrede's learned detector of performance bugs: per component, predict its resource use from
the messages it handles (multi-task Elastic Net), flag a Mahalanobis distance of the residuals above a
threshold set for a target false-positive rate. One job per module:

``encoding`` (messages → numbers), ``features`` (1 Hz windows), ``counters`` (psutil targets),
``ros_tap`` (components and channels from the ROS graph, raw subscriptions), ``zenoh_events`` (the
agents as components, their Zenoh keys as channels, read from the wire), ``record`` and
``scenario`` (data from the real team), ``dataset``, ``model``, ``baselines``, ``metrics``,
``evaluate``, ``observer`` (the online ``resource`` observer) and ``watch`` (it, live). docs/perfbugs.md.
"""
