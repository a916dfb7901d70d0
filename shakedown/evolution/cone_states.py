"""Node-state codes of the 3-D step (shared by the compiled kernels and the tables)."""

STICK, SLIP, SEPARATED = 0, 1, 3
