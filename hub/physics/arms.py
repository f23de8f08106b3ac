"""The world's robot arms: what they grip leaves the dynamics and follows the tool, and triggers ride on their tools."""
from __future__ import annotations

import numpy as np

from hub.core import state
from hub.core.errors import CheckpointError
from hub.physics.robot import KinematicArm


class Arms:
    """Robot arms (robot.py) in the world, the body each one grips (the paper's gripping
    component) and the volume triggers that move with a tool (the paper's gripper trigger)."""

    #: hub/core/state.py: what each arm does and grips (save_state names arms by their place).
    STATE = ("arms", "held")

    def __init__(self, engine, bodies, bottles, triggers):
        self._engine = engine
        self.bodies = bodies
        self.bottles = bottles
        self.triggers = triggers
        self.arms: list[KinematicArm] = []
        self.held: dict[KinematicArm, int] = {}   # arm → the body it grips (never rests)
        self._following: list[tuple[int, KinematicArm, np.ndarray]] = []   # (trigger, arm, offset)

    def add(self, base, yaw: float, tool_length: float) -> KinematicArm:
        arm = KinematicArm(self._engine, base, yaw, tool_length)
        self.arms.append(arm)
        return arm

    def follow(self, trigger: int, arm: KinematicArm, offset) -> None:
        """Make a volume trigger move with the arm's tool."""
        self._following.append((trigger, arm, np.asarray(offset, float)))
        self.triggers.move(trigger, arm.tool_position + offset)

    def grip(self, arm: KinematicArm, body: int) -> None:
        """The body leaves the dynamics and follows the tool (the world announced it first:
        changes.Gripped, which takes it out of free transport and rest)."""
        if body in self.bottles.base_bodies:
            raise NotImplementedError("gripping a bottle with a second base body")
        self.held[arm] = body
        arm.hold(self.bodies.ids[body], self.bodies.positions[body], self.bodies.orientations[body].tolist())

    def release(self, arm: KinematicArm) -> None:
        self.held.pop(arm, None)
        arm.let_go()

    def save_state(self) -> dict:
        return {"arms": [state.save(arm) for arm in self.arms],
                "held": [(self.arms.index(arm), body) for arm, body in self.held.items()]}

    def restore_state(self, saved: dict) -> None:
        if len(saved["arms"]) != len(self.arms):
            raise CheckpointError(f"the snapshot has {len(saved['arms'])} robot arms, this plant {len(self.arms)}")
        for k, (arm, arm_state) in enumerate(zip(self.arms, saved["arms"])):
            state.restore(arm, arm_state, f"world.robots.arms[{k}]")
        self.held = {self.arms[k]: body for k, body in saved["held"]}

    def arm_bodies(self) -> set[int]:
        """The arms' own bodies (their links collide with nothing: robot.py)."""
        return {arm.body for arm in self.arms}

    def held_rows(self) -> list[int]:
        return list(self.held.values())

    def move(self, tick: int) -> None:
        """After a tick: every arm in its pose for `tick`, and the triggers on moving tools with them."""
        moved = [arm for arm in self.arms if arm.update(tick)]
        for trigger, arm, offset in self._following:
            if arm in moved:
                self.triggers.move(trigger, arm.tool_position + offset)
