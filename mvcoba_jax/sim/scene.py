"""Builds the tabletop MJCF from a SceneConfig: table, object slots, floating gripper, cameras.

Contact bits: objects (contype 1) touch everything whose conaffinity has bit 1: other objects,
the table (contype 2), the fingers (4) and the palm (8). Fingers and palm never touch the table
or each other; occluders touch nothing (they only block camera rays). The gripper's geoms are in
their own geom group, which the cameras leave out.
"""
from __future__ import annotations

import dataclasses
import functools

import mujoco
import numpy as np

from mvcoba_jax.sim import shapes
from mvcoba_jax.sim.config import CameraConfig, SceneConfig

PARK_HEIGHT = 2.0  # objects out of play wait here, far above the cameras' view
GRIPPER_PARK = (0.0, 0.0, 1.0)
GRIPPER_GROUP = 3  # geom group of palm and fingers: the cameras leave it out


def park_position(slot: int) -> tuple[float, float, float]:
  """Where out-of-play object `slot` waits: its own spot on a grid high above the table."""
  return (0.6 + 0.15 * (slot % 10), -0.6 + 0.15 * (slot // 10), PARK_HEIGHT)


def _fmt(values) -> str:
  return ' '.join(f'{float(v):.6g}' for v in np.ravel(values))


def camera_xyaxes(cam: CameraConfig) -> np.ndarray:
  """Camera frame x (right) and y (up) axes for a camera at `pos` looking at `target`."""
  forward = np.asarray(cam.target, float) - np.asarray(cam.pos, float)
  forward /= np.linalg.norm(forward)
  right = np.cross(forward, [0.0, 0.0, 1.0])
  if np.linalg.norm(right) < 1e-6:  # looking straight down: pick +x as right
    right = np.array([1.0, 0.0, 0.0])
  right /= np.linalg.norm(right)
  up = np.cross(right, forward)
  return np.concatenate([right, up])


def slot_shapes(scene: SceneConfig) -> tuple[str, ...]:
  """Shape name of every object slot, in slot order."""
  return tuple(name for name, count in scene.pool for _ in range(count))


def build_mjcf(scene: SceneConfig) -> str:
  slots = slot_shapes(scene)
  kinds = list(dict.fromkeys(slots))  # each shape's meshes once, named by its place here
  meshes = '\n'.join(
      f'    <mesh name="m{k}_{j}" vertex="{_fmt(part.vertices)}"/>'
      for k, name in enumerate(kinds) for j, part in enumerate(shapes.shape(name).parts)
      if part.kind == 'mesh')

  bodies = []
  for i, shape_name in enumerate(slots):
    geoms = []
    for j, part in enumerate(shapes.shape(shape_name).parts):
      where = f'name="obj{i}_{j}" pos="{_fmt(part.pos)}"'
      if part.kind == 'box':
        geoms.append(f'<geom {where} type="box" size="{_fmt(part.half_size)}"/>')
      else:
        geoms.append(f'<geom {where} type="mesh" mesh="m{kinds.index(shape_name)}_{j}"/>')
    bodies.append(f'    <body name="obj{i}" pos="{_fmt(park_position(i))}">'
                  f'<freejoint name="obj{i}"/>{"".join(geoms)}</body>')

  cameras = '\n'.join(
      f'    <camera name="cam{i}" pos="{_fmt(c.pos)}" xyaxes="{_fmt(camera_xyaxes(c))}" '
      f'fovy="{c.fovy_deg:.6g}"/>' for i, c in enumerate(scene.cameras))
  occluders = '\n'.join(
      f'    <body name="occluder{i}" mocap="true" pos="{_fmt((-1.0 - i, -2.0, PARK_HEIGHT))}">'
      f'<geom name="occluder{i}" type="box" size="{_fmt(h)}" contype="0" conaffinity="0" '
      f'rgba="0.35 0.35 0.35 1"/></body>' for i, h in enumerate(scene.occluders))

  gripper = scene.gripper
  fx, fy, fz = (0.5 * gripper.finger_width, 0.5 * gripper.finger_thickness,
                0.5 * gripper.finger_length)
  palm = tuple(0.5 * v for v in gripper.palm)
  finger_friction = f'{gripper.finger_friction:.6g} 0.005 0.0001'
  force = f'{-gripper.finger_force:.6g} {gripper.finger_force:.6g}'
  return f"""<mujoco model="mvcoba_tabletop">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{scene.timestep:.6g}" iterations="{scene.iterations}"
          ls_iterations="{scene.ls_iterations}" noslip_iterations="{scene.noslip_iterations}"
          solver="Newton" jacobian="sparse"
          cone="pyramidal" integrator="implicitfast"/>
  <custom>
    <numeric name="max_contact_points" data="{scene.max_contact_points}"/>
    <numeric name="max_geom_pairs" data="{scene.max_geom_pairs}"/>
  </custom>
  <default>
    <geom condim="3" contype="1" conaffinity="1" friction="{scene.friction:.6g} 0.005 0.0001"
          solref="{scene.contact_timeconst:.6g} 1"
          density="{scene.object_density:.6g}" material="plain"/>
  </default>
  <asset>
    <material name="plain" rgba="1 1 1 1"/>
{meshes}
  </asset>
  <worldbody>
    <geom name="table" type="plane" size="1 1 0.01" contype="2" conaffinity="1"
          rgba="0.8 0.8 0.8 1"/>
{cameras}
    <body name="gripper" gravcomp="1">
      <joint name="grip_x" type="slide" axis="1 0 0" armature="0.1"/>
      <joint name="grip_y" type="slide" axis="0 1 0" armature="0.1"/>
      <joint name="grip_z" type="slide" axis="0 0 1" armature="0.1"/>
      <joint name="grip_yaw" type="hinge" axis="0 0 1" armature="0.01"/>
      <geom name="palm" type="box" pos="0 0 {2 * fz + palm[2]:.6g}" size="{_fmt(palm)}"
            contype="8" mass="0.4" group="{GRIPPER_GROUP}"/>
      <body name="finger_left" gravcomp="1">
        <joint name="finger_left" type="slide" axis="0 1 0"
               range="0 {gripper.max_opening / 2:.6g}"
               armature="0.01"/>
        <geom name="finger_left" type="box" pos="0 {fy:.6g} {fz:.6g}" size="{_fmt((fx, fy, fz))}"
              contype="4" mass="0.05" friction="{finger_friction}" group="{GRIPPER_GROUP}"/>
      </body>
      <body name="finger_right" gravcomp="1">
        <joint name="finger_right" type="slide" axis="0 -1 0"
               range="0 {gripper.max_opening / 2:.6g}"
               armature="0.01"/>
        <geom name="finger_right" type="box" pos="0 {-fy:.6g} {fz:.6g}" size="{_fmt((fx, fy, fz))}"
              contype="4" mass="0.05" friction="{finger_friction}" group="{GRIPPER_GROUP}"/>
      </body>
    </body>
{chr(10).join(bodies)}
{occluders}
  </worldbody>
  <actuator>
    <position name="grip_x" joint="grip_x" kp="3000" kv="150" forcerange="-60 60"/>
    <position name="grip_y" joint="grip_y" kp="3000" kv="150" forcerange="-60 60"/>
    <position name="grip_z" joint="grip_z" kp="3000" kv="150"
              forcerange="{-scene.press_force:.6g} 60"/>
    <position name="grip_yaw" joint="grip_yaw" kp="30" kv="2" forcerange="-5 5"/>
    <position name="finger_left" joint="finger_left" kp="400" kv="10" forcerange="{force}"/>
    <position name="finger_right" joint="finger_right" kp="400" kv="10" forcerange="{force}"/>
  </actuator>
</mujoco>
"""


@dataclasses.dataclass(frozen=True)
class SceneIndex:
  """Addresses into qpos/qvel/ctrl and geom ids, fixed for a compiled scene."""
  slot_shapes: tuple[str, ...]
  slot_qpos: np.ndarray  # (M,) first qpos address of each slot's free joint
  slot_qvel: np.ndarray  # (M,)
  gripper_qpos: np.ndarray  # (6,) x, y, z, yaw, finger_left, finger_right
  gripper_qvel: np.ndarray  # (6,)
  geom_slot: np.ndarray  # (ngeom,) object slot of each geom, -1 for other geoms
  gripper_geoms: np.ndarray  # geom ids of palm and fingers
  occluder_mocap: np.ndarray  # (K,) mocap ids of occluder bodies


@dataclasses.dataclass(frozen=True)
class Scene:
  mj_model: mujoco.MjModel
  index: SceneIndex
  config: SceneConfig


def _index(m: mujoco.MjModel, scene: SceneConfig) -> SceneIndex:
  slots = slot_shapes(scene)
  jid = lambda name: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
  gripper_joints = [jid(n) for n in
                    ('grip_x', 'grip_y', 'grip_z', 'grip_yaw', 'finger_left', 'finger_right')]
  obj_joints = [jid(f'obj{i}') for i in range(len(slots))]
  geom_slot = np.full(m.ngeom, -1, np.int32)
  for i in range(len(slots)):
    body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f'obj{i}')
    geom_slot[m.geom_bodyid == body] = i
  gid = lambda name: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, name)
  occluder_bodies = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f'occluder{i}')
                     for i in range(len(scene.occluders))]
  return SceneIndex(
      slot_shapes=slots,
      slot_qpos=np.array([m.jnt_qposadr[j] for j in obj_joints], np.int32),
      slot_qvel=np.array([m.jnt_dofadr[j] for j in obj_joints], np.int32),
      gripper_qpos=np.array([m.jnt_qposadr[j] for j in gripper_joints], np.int32),
      gripper_qvel=np.array([m.jnt_dofadr[j] for j in gripper_joints], np.int32),
      geom_slot=geom_slot,
      gripper_geoms=np.array([gid('palm'), gid('finger_left'), gid('finger_right')], np.int32),
      occluder_mocap=np.array([m.body_mocapid[b] for b in occluder_bodies], np.int32),
  )


@functools.lru_cache(maxsize=8)
def build_scene(scene: SceneConfig) -> Scene:
  """Compiled MuJoCo model and the address index (cached per config)."""
  if scene.num_slots == 0:
    raise ValueError('scene.pool holds no object slots')
  mj_model = mujoco.MjModel.from_xml_string(build_mjcf(scene))
  return Scene(mj_model=mj_model, index=_index(mj_model, scene), config=scene)
