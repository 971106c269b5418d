"""regrasp.study.study."""
