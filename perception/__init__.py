"""faultmas: perception."""
