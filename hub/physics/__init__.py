"""The material-flow physics: every pybullet call of planthub is in this package; `PhysicsWorld` (world.py) puts its parts together."""
from hub.physics.world import PhysicsWorld

__all__ = ["PhysicsWorld"]
