"""regrasp.rollout.build."""
