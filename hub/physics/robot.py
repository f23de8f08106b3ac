"""A kinematic robot arm (the KUKA iiwa of pybullet_data): joints set per tick, gripped bodies follow the tool."""
from __future__ import annotations

import math

import numpy as np

from hub.core import state
from hub.physics._quiet import quiet_stderr
from hub.physics.engine import DYNAMIC

with quiet_stderr():
    import pybullet
    import pybullet_data

URDF = "kuka_iiwa/model.urdf"
FLANGE = 6                      # lbr_iiwa_link_7: the tool sits on its frame, along its z axis
JOINTS = 7
SHOULDER = (0.0, 0.0, 0.36)     # joint 2 above the base: the centre of the reach envelope
REACH = 0.78                    # m from the shoulder to the flange, a little inside the arm's stretch
DOWN = (0.0, 1.0, 0.0, 0.0)     # tool axis pointing down: rotation by π about y
# A comfortable elbow-up rest pose that the null-space solver pulls towards, so that every pose
# of one arm comes out on the same branch and joint interpolation between them stays short.
REST = (0.0, 0.5, 0.0, -1.5, 0.0, 1.1, 0.0)
#: solutions found in this process: (base, yaw, tool length, point) → (joints, miss). A solve
#: depends on nothing else (it starts from REST, within the URDF's limits), so an arm built again
#: in one process — a campaign zygote's forked cases, a test's second run — does not redo its
#: 40 solver calls per pose.
_SOLVED: dict[tuple, tuple[np.ndarray, float]] = {}


def reachable(base, point, tool_length: float) -> bool:
    """Cheap envelope test for a tool point (pointing down), before any inverse kinematics."""
    flange = np.asarray(point, float) + (0.0, 0.0, tool_length)
    return bool(np.linalg.norm(flange - np.asarray(base, float) - SHOULDER) <= REACH)


def smooth(s: np.ndarray | float):
    """Quintic time scaling 10s³ − 15s⁴ + 6s⁵ and its derivative: starts and ends at rest with
    zero acceleration, so a gripped body is never jerked and is released at the tool's speed."""
    s2 = s * s
    return s2 * s * (10.0 - 15.0 * s + 6.0 * s2), 30.0 * s2 * (1.0 - s) ** 2


@state.value
class JointMotion:
    """A straight line in joint space from `q0` to `q1`, over `ticks` ticks from `start` (exclusive)."""

    def __init__(self, q0, q1, start: int, ticks: int, rate: int):
        self.q0 = np.asarray(q0, float)
        self.dq = np.asarray(q1, float) - self.q0
        self.start = start
        self.ticks = max(1, ticks)
        self.rate = rate

    @property
    def end(self) -> int:
        return self.start + self.ticks

    def at(self, tick: int) -> tuple[np.ndarray, np.ndarray]:
        """Joint positions and velocities at `tick`, from the integer tick count (no accumulated time)."""
        s = min(1.0, max(0.0, (tick - self.start) / self.ticks))
        pos, vel = smooth(s)
        return self.q0 + self.dq * pos, self.dq * (vel * self.rate / self.ticks)


class KinematicArm:
    """A fixed-base arm that the engine never integrates: it is asleep and has no collision
    shapes in play (the paper's arm is an animation), and its joints are set at every tick while
    a motion plays. Measured on the 2-core machine (bare pybullet): asleep it adds 1.8 µs per
    tick to the engine (15.5 µs awake, and it drifts 0.004 rad in 10 s under its motors);
    moving it adds ~10 µs per tick (`make bench`) and tracks exactly, where position-controlled
    motors lag 0.09 rad on the same move at 44 µs per tick. A gripped body leaves the dynamics
    (collision off) and is put at the tool every tick; released, it collides again with the
    tool's velocity. Setting joints and bodies in the loop is deterministic as long as the
    sequence of calls is (tests/test_robot_arm.py runs the robot scenario three times, once in
    another process, and compares the bytes).
    """

    STATE = ("motion", "held", "q", "tool_position", "tool_velocity")   # hub/core/state.py

    def __init__(self, engine, base, yaw: float, tool_length: float):
        self._engine = engine
        self._client = engine.client
        self.base = np.asarray(base, float)
        self.yaw = yaw
        self.tool_length = tool_length
        self._id = self._call(pybullet.loadURDF, f"{pybullet_data.getDataPath()}/{URDF}", list(base),
                              pybullet.getQuaternionFromEuler((0.0, 0.0, yaw)), useFixedBase=True)
        info = [self._call(pybullet.getJointInfo, self._id, j) for j in range(JOINTS)]
        self.joint_names = [i[1].decode("utf-8") for i in info]
        self.lower = np.array([i[8] for i in info])
        self.upper = np.array([i[9] for i in info])
        for link in range(-1, JOINTS):
            self._call(pybullet.setCollisionFilterGroupMask, self._id, link, 0, 0)
        self._call(pybullet.changeDynamics, self._id, -1, activationState=pybullet.ACTIVATION_STATE_ENABLE_SLEEPING)
        self._call(pybullet.changeDynamics, self._id, -1, activationState=pybullet.ACTIVATION_STATE_SLEEP)
        self.motion: JointMotion | None = None
        self.held: tuple[int, np.ndarray, tuple] | None = None   # (pybullet id, offset from tool, orientation)
        self.q = np.array(REST)
        self.tool_position = np.zeros(3)
        self.tool_velocity = np.zeros(3)
        self.set(self.q, np.zeros(JOINTS))

    @property
    def body(self) -> int:
        return self._id

    def _call(self, fn, *args, **kwargs):
        return fn(*args, physicsClientId=self._client, **kwargs)

    # --- poses ----------------------------------------------------------------------------
    def solve(self, point) -> tuple[np.ndarray, float]:
        """Joint positions that put the tool at `point` pointing down, and the miss in metres.

        Two stages, both deterministic: a null-space solve within the joint limits near the rest
        pose (it stops ~1 mm short, pulled by the rest pose), then plain solves from there,
        which close the gap to below a micrometre."""
        key = (tuple(self.base.tolist()), self.yaw, self.tool_length, tuple(np.asarray(point, float).tolist()))
        if key not in _SOLVED:
            _SOLVED[key] = self._solve(point)
        else:   # the arm left as a solve leaves it: where it was, at rest
            self.set(self.q.copy(), np.zeros(JOINTS))
        q, miss = _SOLVED[key]
        return q.copy(), miss

    def _solve(self, point) -> tuple[np.ndarray, float]:
        flange = (np.asarray(point, float) + (0.0, 0.0, self.tool_length)).tolist()
        saved = self.q.copy()
        span = (self.upper - self.lower).tolist()
        q = np.array(REST)
        for _ in range(20):
            self._set_joints(q)
            q = np.array(self._call(pybullet.calculateInverseKinematics, self._id, FLANGE, flange, DOWN,
                                    lowerLimits=self.lower.tolist(), upperLimits=self.upper.tolist(),
                                    jointRanges=span, restPoses=list(REST),
                                    maxNumIterations=200, residualThreshold=1e-9))
        for _ in range(20):
            self._set_joints(q)
            q = np.array(self._call(pybullet.calculateInverseKinematics, self._id, FLANGE, flange, DOWN,
                                    maxNumIterations=50, residualThreshold=1e-10))
        self._set_joints(q)
        miss = float(np.linalg.norm(self._tool()[0] - point))
        if np.any(q < self.lower) or np.any(q > self.upper):
            miss = math.inf
        self.set(saved, np.zeros(JOINTS))
        return q, miss

    # --- motion ---------------------------------------------------------------------------
    def play(self, motion: JointMotion) -> None:
        self.motion = motion

    @property
    def moving(self) -> bool:
        return self.motion is not None

    def update(self, tick: int) -> bool:
        """Called by the world after every physics tick: the arm's pose for this tick, and the
        held body put at the tool. Returns whether the tool moved."""
        motion = self.motion
        if motion is None:
            if self.held is not None:
                self._carry()   # still, the held body must not fall: it is out of the dynamics
            return False
        q, qd = motion.at(tick)
        if tick >= motion.end:
            self.motion = None
            qd = np.zeros(JOINTS)
        self.set(q, qd)
        return True

    def set(self, q, qd) -> None:
        self.q = np.asarray(q, float)
        self._set_joints(self.q, qd)
        self.tool_position, self.tool_velocity = self._tool()
        if self.held is not None:
            self._carry()

    def _carry(self) -> None:
        """Put the held body at the tool (the paper's data flow from gripper pose to bottle pose)."""
        body, offset, orientation = self.held
        self._call(pybullet.resetBasePositionAndOrientation, body, (self.tool_position + offset).tolist(), orientation)
        self._call(pybullet.resetBaseVelocity, body, self.tool_velocity.tolist(), (0.0, 0.0, 0.0))

    def _set_joints(self, q, qd=None) -> None:
        qd = np.zeros(JOINTS) if qd is None else qd
        self._call(pybullet.resetJointStatesMultiDof, self._id, list(range(JOINTS)),
                   [[v] for v in np.asarray(q, float).tolist()], targetVelocities=[[v] for v in np.asarray(qd).tolist()])

    def _tool(self) -> tuple[np.ndarray, np.ndarray]:
        """Tool point and its linear velocity: v = v_com + ω × (p_tool − p_com) of the flange link."""
        state = self._call(pybullet.getLinkState, self._id, FLANGE, computeLinkVelocity=1, computeForwardKinematics=1)
        # Plain floats: this runs every tick while the arm moves, and numpy on three numbers
        # costs more than the pybullet calls (a world with a moving arm: 125 µs per tick with
        # np.cross here, 40 µs without).
        (cx, cy, cz), (fx, fy, fz), m = state[0], state[4], pybullet.getMatrixFromQuaternion(state[5])
        length = self.tool_length
        tx, ty, tz = fx + length * m[2], fy + length * m[5], fz + length * m[8]   # the flange's z axis
        (vx, vy, vz), (wx, wy, wz) = state[6], state[7]
        rx, ry, rz = tx - cx, ty - cy, tz - cz
        velocity = (vx + wy * rz - wz * ry, vy + wz * rx - wx * rz, vz + wx * ry - wy * rx)
        return np.array((tx, ty, tz)), np.array(velocity)

    # --- gripping -------------------------------------------------------------------------
    def hold(self, body: int, position, orientation) -> None:
        """Take a body (pybullet id) out of the dynamics and keep it where it is relative to the tool."""
        self._engine.set_filter(body, -1, 0, 0)
        self.held = (body, np.asarray(position, float) - self.tool_position, tuple(orientation))

    def let_go(self) -> int | None:
        """Give the held body back to the dynamics with the tool's velocity; returns its pybullet id."""
        if self.held is None:
            return None
        body = self.held[0]
        self.held = None
        self._call(pybullet.resetBaseVelocity, body, self.tool_velocity.tolist(), (0.0, 0.0, 0.0))
        self._engine.set_filter(body, -1, *DYNAMIC)
        return body
