"""The material-flow physics: the only place that talks to pybullet is `world.py`."""
from hub.physics.world import PhysicsWorld

__all__ = ["PhysicsWorld"]
