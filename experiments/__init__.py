"""Experiments that reproduce a paper's table, each run by ``faultmas experiment NAME`` (see ``experiments.cli``)."""
