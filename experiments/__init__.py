"""Experiments that reproduce a paper's table: one module each, run by ``faultmas experiment NAME``."""
