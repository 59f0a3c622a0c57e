"""faultmas: plans."""
