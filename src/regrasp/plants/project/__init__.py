"""regrasp.plants.project."""
