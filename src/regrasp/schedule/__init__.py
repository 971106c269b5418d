"""regrasp.schedule.schedule."""
