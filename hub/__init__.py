"""planthub: a co-simulation hub for automation plants."""
