"""Scripted gripper controller for the two primitives, as a pure function of the step index.

Both primitives run for the same number of physics steps (the longer script's length) so that a
batch of environments executing different primitives stays in lockstep; the shorter script holds
its last target. Targets are (x, y, z, yaw, finger_left, finger_right) for the position actuators;
z is the fingertip height.
"""
from __future__ import annotations

import math

import jax.numpy as jnp
from flax import struct

from mvcoba_jax.sim.config import EnvConfig, GripperConfig
from mvcoba_jax.sim.geometry import rotation_angle
from mvcoba_jax.sim.contract import GRASP, PUSH, push_length  # noqa: F401  (primitives.PUSH)

FINGER_SQUEEZE = -0.01  # target past closed: the fingers keep squeezing what they hold


@struct.dataclass
class Action:
  """One primitive at a world point: `z` is the surface height there (from the heightmap)."""
  primitive: jnp.ndarray  # int32: PUSH or GRASP
  rotation: jnp.ndarray  # int32 in [0, num_rotations)
  x: jnp.ndarray
  y: jnp.ndarray
  z: jnp.ndarray


def _steps(duration: float, dt: float) -> int:
  return max(1, int(math.ceil(duration / dt - 1e-9)))


@struct.dataclass
class Script:
  """Step counts of each phase, fixed at trace time."""
  descend: int = struct.field(pytree_node=False)
  close: int = struct.field(pytree_node=False)
  lift: int = struct.field(pytree_node=False)
  hold: int = struct.field(pytree_node=False)
  push: int = struct.field(pytree_node=False)

  @property
  def grasp_length(self) -> int:
    return self.descend + self.close + self.lift + self.hold

  @property
  def push_length(self) -> int:
    return self.descend + self.push + self.hold

  @property
  def length(self) -> int:
    return max(self.grasp_length, self.push_length)


def make_script(env: EnvConfig, dt: float) -> Script:
  return Script(
      descend=_steps(env.approach_height / env.descend_speed, dt),
      close=_steps(env.close_time, dt),
      lift=_steps(env.lift_height / env.lift_speed, dt),
      hold=_steps(env.hold_time, dt),
      push=_steps(env.push_length / env.push_speed, dt))


def tip_heights(action: Action, env: EnvConfig):
  """(start, working) fingertip heights: grasp 3 cm into the surface, push just above the table."""
  grasp_tip = jnp.maximum(action.z - env.grasp_depth, env.min_tip_height)
  work = jnp.where(action.primitive == GRASP, grasp_tip, env.push_height)
  start = jnp.maximum(action.z, work) + env.approach_height
  return start, work


def finger_open(gripper: GripperConfig) -> float:
  """Each finger's joint position with the gripper open: half the opening."""
  return gripper.max_opening / 2


def start_pose(action: Action, env: EnvConfig, gripper: GripperConfig):
  """Gripper joint positions the primitive starts from (the gripper is placed there)."""
  start, _ = tip_heights(action, env)
  yaw = rotation_angle(action.rotation, env.num_rotations)
  finger = jnp.where(action.primitive == GRASP, finger_open(gripper), 0.0)
  return jnp.stack([action.x, action.y, start, yaw, finger, finger])


def target(script: Script, action: Action, env: EnvConfig, gripper: GripperConfig, half: float,
           t):
  """Actuator targets at physics step t of the primitive; a push stops at the workspace's edge
  (+-`half`), as the robot's does (`sim.contract.push_length`)."""
  start, work = tip_heights(action, env)
  yaw = rotation_angle(action.rotation, env.num_rotations)
  ramp = lambda t0, n: jnp.clip((t - t0 + 1) / n, 0.0, 1.0)
  descend = start + (work - start) * ramp(0, script.descend)

  # Grasp: descend open, close, lift.
  # The fingers close at a bounded speed: a fast close tunnels through corners.
  lift = ramp(script.descend + script.close, script.lift) * env.lift_height
  grasp_z = descend + lift
  open_ = finger_open(gripper)
  grasp_finger = open_ + (FINGER_SQUEEZE - open_) * ramp(script.descend, script.close)

  # Push: descend closed, slide along the rotation's direction.
  reach = push_length((action.x, action.y), yaw, env.push_length, half, xp=jnp)
  along = jnp.minimum(ramp(script.descend, script.push) * env.push_length, reach)
  push_x = action.x + along * jnp.cos(yaw)
  push_y = action.y + along * jnp.sin(yaw)

  is_grasp = action.primitive == GRASP
  x = jnp.where(is_grasp, action.x, push_x)
  y = jnp.where(is_grasp, action.y, push_y)
  z = jnp.where(is_grasp, grasp_z, descend)
  finger = jnp.where(is_grasp, grasp_finger, FINGER_SQUEEZE)
  return jnp.stack([x, y, z, yaw, finger, finger])
