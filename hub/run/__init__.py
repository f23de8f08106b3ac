"""A run: the one assembly, the plant build, the master, co-simulation algorithms, observers, stop conditions, pacing and the Python API."""
