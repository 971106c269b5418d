"""regrasp.core."""
