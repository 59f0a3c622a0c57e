"""faultmas: agentspeak."""
