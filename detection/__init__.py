"""What finds faults in a running system: taps, observers and the learned detector; feeds ``diagnosis``."""
