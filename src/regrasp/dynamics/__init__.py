"""regrasp.dynamics."""
