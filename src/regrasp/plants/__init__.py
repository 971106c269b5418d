"""regrasp.plants."""
