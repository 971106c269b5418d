"""``regrasp.cli``: the command line (``regrasp plan | simulate | study``; :func:`regrasp.cli.main.main`)."""
