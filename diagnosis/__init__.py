"""faultmas: diagnosis."""
