"""regrasp.dynamics.internal_force."""
