"""regrasp.rollout.build.recording."""
