"""regrasp.plants.mujoco."""
