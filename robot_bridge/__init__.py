"""faultmas: robot_bridge."""
