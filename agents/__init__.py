"""faultmas: agents."""
