"""The material-flow physics: the only place that talks to pybullet is `world.py`."""
from .world import PhysicsWorld

__all__ = ["PhysicsWorld"]
