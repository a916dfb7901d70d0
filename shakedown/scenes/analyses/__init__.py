"""Command-line analyses: one module per ``[analyses.<name>]`` table (``OPTIONS``, ``run``)."""
