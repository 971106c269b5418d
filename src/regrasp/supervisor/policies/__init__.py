"""regrasp.supervisor.supervisor.policies."""
