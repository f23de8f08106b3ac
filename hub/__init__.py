"""planthub: a co-simulation hub for automation plants.

`from hub import Simulation` is the Python API (hub/run/simulation.py); hub/README.md says where the rest lives."""


def __getattr__(name):
    # Imported on first use, so `import hub` stays light for the modules that build on it.
    if name == "Simulation":
        from hub.run.simulation import Simulation

        return Simulation
    if name == "__version__":
        from importlib.metadata import version

        return version("planthub")   # the installed distribution's, from pyproject.toml
    raise AttributeError(f"module 'hub' has no attribute {name!r}")
