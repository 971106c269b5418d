"""regrasp.cli.main."""
