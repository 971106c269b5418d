"""regrasp.model."""
