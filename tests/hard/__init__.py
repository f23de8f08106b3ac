"""Hard cases of the co-simulation (issue 14): each test file one case."""
