"""faultmas benchmarks: speed and memory targets, measured side by side, printed as tables."""
