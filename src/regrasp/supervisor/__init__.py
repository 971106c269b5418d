"""regrasp.supervisor.supervisor."""
