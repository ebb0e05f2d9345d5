"""The batched tabletop environment: pure `reset`, `reset_from_case` and `step` over a pytree state.

Every function here works on one environment and is jittable; vmap it over B environments
(`jax.vmap(env.step)`). Object slots not in play are pinned at their parking spots on every physics
step, so they never touch anything and never count.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct
from mujoco import mjx

from envs import primitives, shapes
from envs.primitives import Action
from envs.scene import GRIPPER_PARK, build_scene, park_position
from mvcoba_jax.config import Config
from mvcoba_jax.geometry import quat_mul, yaw_quat

PLACEMENT_TRIES = 16  # candidate spots per object and drop layer
PLACEMENT_GAP = 0.004  # clearance between footprint circles of objects dropped in one layer


@struct.dataclass
class Layout:
  """Where each object slot starts: a random drop or a test case (padded to the slot count)."""
  in_play: jnp.ndarray  # (M,) bool
  pos: jnp.ndarray  # (M, 3)
  quat: jnp.ndarray  # (M, 4) w, x, y, z
  color: jnp.ndarray  # (M, 3) RGB 0..1
  occluder_pos: jnp.ndarray  # (K, 3)
  occluder_quat: jnp.ndarray  # (K, 4)


@struct.dataclass
class EnvState:
  data: mjx.Data
  in_play: jnp.ndarray  # (M,) bool: on the table and not yet picked or lost
  color: jnp.ndarray  # (M, 3)
  picked: jnp.ndarray  # int32: objects picked this episode
  lost: jnp.ndarray  # int32: objects that left the workspace this episode
  healthy: jnp.ndarray  # bool: physics finite and not exploded after the last reset/step
  health_resets: jnp.ndarray  # int32: times this environment was reset for bad physics
  key: jnp.ndarray


@struct.dataclass
class StepInfo:
  grasp_success: jnp.ndarray  # bool
  picked: jnp.ndarray  # int32: objects removed by this grasp
  lost: jnp.ndarray  # int32: objects that left the workspace during this step
  left_workspace: jnp.ndarray  # (M,) bool: which objects those were
  healthy: jnp.ndarray  # bool


def where_envs(mask, new, old):
  """Per-environment choice between two batched pytrees: `new` where `mask` (B,) holds."""
  return jax.tree.map(
      lambda a, b: jnp.where(mask.reshape(mask.shape + (1,) * (a.ndim - 1)), a, b), new, old)


class Tabletop:
  """Static description of the environment; its methods are pure functions of the state."""

  def __init__(self, config: Config):
    self.config = config
    self.scene = build_scene(config.scene)
    self.model = self.scene.model
    idx = self.scene.index
    self.num_slots = len(idx.slot_shapes)
    if config.env.num_objects > self.num_slots:
      raise ValueError(f'env.num_objects={config.env.num_objects} exceeds the '
                       f'{self.num_slots} object slots of scene.pool')
    self.script = primitives.make_script(config.env, config.scene.timestep)
    self._qpos_idx = jnp.asarray(idx.slot_qpos[:, None] + np.arange(7))
    self._qvel_idx = jnp.asarray(idx.slot_qvel[:, None] + np.arange(6))
    self._grip_qpos = jnp.asarray(idx.gripper_qpos)
    self._grip_qvel = jnp.asarray(idx.gripper_qvel)
    park = np.array([park_position(i) + (1.0, 0.0, 0.0, 0.0) for i in range(self.num_slots)])
    self._park_qpos = jnp.asarray(park, jnp.float32)
    self._gripper_park = jnp.array(GRIPPER_PARK + (0.0, primitives.FINGER_OPEN,
                                                   primitives.FINGER_OPEN), jnp.float32)
    slot_shapes = [shapes.SHAPES[s] for s in idx.slot_shapes]
    self._rest_quat = jnp.asarray([s.rest_quat for s in slot_shapes], jnp.float32)
    self._rest_half_height = jnp.asarray([0.5 * s.rest_extent[2] for s in slot_shapes],
                                         jnp.float32)
    self._radius = jnp.asarray([shapes.footprint_radius(s.name) for s in slot_shapes],
                               jnp.float32)

  # ----------------------------------------------------------------------------- physics core
  def _pin(self, data: mjx.Data, in_play) -> mjx.Data:
    """Holds out-of-play slots at their parking spots, at rest."""
    qpos = data.qpos.at[self._qpos_idx].set(
        jnp.where(in_play[:, None], data.qpos[self._qpos_idx], self._park_qpos))
    qvel = data.qvel.at[self._qvel_idx].set(
        jnp.where(in_play[:, None], data.qvel[self._qvel_idx], 0.0))
    return data.replace(qpos=qpos, qvel=qvel)

  def _place_gripper(self, data: mjx.Data, pose) -> mjx.Data:
    """Puts the gripper at `pose` (x, y, z, yaw, fingers) at rest, with targets there too."""
    return data.replace(qpos=data.qpos.at[self._grip_qpos].set(pose),
                        qvel=data.qvel.at[self._grip_qvel].set(0.0),
                        ctrl=pose)

  def _simulate(self, data: mjx.Data, in_play, ctrl_fn, num_steps: int) -> mjx.Data:
    def body(d, t):
      d = mjx.step(self.model, d.replace(ctrl=ctrl_fn(t)))
      return self._pin(d, in_play), None
    data, _ = jax.lax.scan(body, data, jnp.arange(num_steps))
    return data

  def _health(self, data: mjx.Data):
    finite = jnp.all(jnp.isfinite(data.qpos)) & jnp.all(jnp.isfinite(data.qvel))
    return finite & (jnp.max(jnp.abs(data.qvel)) < self.config.env.max_qvel)

  def _in_workspace(self, data: mjx.Data):
    pos = data.qpos[self._qpos_idx[:, :3]]
    h = self.config.scene.workspace_half
    return (jnp.abs(pos[:, 0]) <= h) & (jnp.abs(pos[:, 1]) <= h) & (pos[:, 2] > -0.05)

  def _finish(self, data: mjx.Data, in_play) -> mjx.Data:
    """Parks the gripper and removed objects; refreshes positions for rendering."""
    data = self._pin(self._place_gripper(data, self._gripper_park), in_play)
    return mjx.camlight(self.model, mjx.kinematics(self.model, data))

  # ----------------------------------------------------------------------------- reset
  def sample_layout(self, key) -> Layout:
    """A random drop of `env.num_objects` objects: greedy non-overlapping spots in stacked layers.

    Objects that do not fit beside the others go to a layer `layer_height` higher and fall onto
    the pile while the scene settles, as sequential drops would.
    """
    env, m = self.config.env, self.num_slots
    n = env.num_objects
    layers = 1 + n // 4
    k_perm, k_place, k_yaw, k_color = jax.random.split(key, 4)
    order = jax.random.permutation(k_perm, m)
    in_play = jnp.zeros(m, bool).at[order[:n]].set(True)
    lim = self.config.scene.workspace_half - env.drop_margin
    cands = jax.random.uniform(k_place, (n, layers * PLACEMENT_TRIES, 2), minval=-lim, maxval=lim)
    cand_layer = jnp.repeat(jnp.arange(layers), PLACEMENT_TRIES)

    def place(i, carry):
      xy, layer, placed = carry
      s = order[i]
      dist = jnp.linalg.norm(cands[i][:, None, :] - xy[None], axis=-1)
      clash = placed[None] & (layer[None] == cand_layer[:, None]) & (
          dist < self._radius[s] + self._radius[None] + PLACEMENT_GAP)
      free = ~jnp.any(clash, axis=1)
      j = jnp.where(jnp.any(free), jnp.argmax(free), free.shape[0] - 1)
      return xy.at[s].set(cands[i, j]), layer.at[s].set(cand_layer[j]), placed.at[s].set(True)

    xy, layer, _ = jax.lax.fori_loop(
        0, n, place, (jnp.zeros((m, 2)), jnp.zeros(m, jnp.int32), jnp.zeros(m, bool)))
    z = self._rest_half_height + 0.002 + layer * env.layer_height
    pos = jnp.where(in_play[:, None], jnp.concatenate([xy, z[:, None]], axis=1),
                    self._park_qpos[:, :3])
    yaw = jax.random.uniform(k_yaw, (m,), maxval=2 * jnp.pi)
    quat = quat_mul(yaw_quat(yaw), self._rest_quat)
    color = jnp.asarray(shapes.COLORS)[jax.random.permutation(k_color, jnp.arange(m) % 10)]
    occluder_pos, occluder_quat = self.parked_occluders()
    return Layout(in_play=in_play, pos=pos, quat=quat, color=color,
                  occluder_pos=occluder_pos, occluder_quat=occluder_quat)

  def parked_occluders(self):
    """Poses of the occluder slots when a layout uses none of them: at their model positions."""
    mj = self.scene.mj_model
    bodies = np.flatnonzero(mj.body_mocapid >= 0)[np.argsort(mj.body_mocapid[mj.body_mocapid >= 0])]
    return jnp.asarray(mj.body_pos[bodies], jnp.float32), jnp.asarray(mj.body_quat[bodies],
                                                                        jnp.float32)

  def reset(self, key) -> EnvState:
    """Drops `env.num_objects` random objects and lets them settle."""
    key, k_layout = jax.random.split(key)
    return self.reset_from_case(self.sample_layout(k_layout), key)

  def place(self, layout: Layout, key=None) -> EnvState:
    """The objects of `layout` exactly where it puts them, without physics (for pictures)."""
    if key is None:
      key = jax.random.PRNGKey(0)
    data = mjx.make_data(self.model, device=jax.local_devices()[0])
    qpos = data.qpos.at[self._qpos_idx].set(
        jnp.where(layout.in_play[:, None], jnp.concatenate([layout.pos, layout.quat], 1),
                  self._park_qpos))
    mocap = self.scene.index.occluder_mocap
    data = data.replace(qpos=qpos,
                        mocap_pos=data.mocap_pos.at[mocap].set(layout.occluder_pos),
                        mocap_quat=data.mocap_quat.at[mocap].set(layout.occluder_quat))
    return EnvState(data=self._finish(data, layout.in_play), in_play=layout.in_play,
                    color=layout.color, picked=jnp.int32(0), lost=jnp.int32(0),
                    healthy=self._health(data), health_resets=jnp.int32(0), key=key)

  def reset_from_case(self, layout: Layout, key=None) -> EnvState:
    """Places the objects of `layout` (a test case or a random drop) and lets them settle."""
    state = self.place(layout, key)
    park = self._gripper_park
    data = self._simulate(state.data, state.in_play, lambda t: park, self.config.env.settle_steps)
    in_play = state.in_play & self._in_workspace(data)
    return state.replace(data=self._finish(data, in_play), in_play=in_play,
                         healthy=self._health(data))

  # ----------------------------------------------------------------------------- step
  def step(self, state: EnvState, action: Action) -> tuple[EnvState, StepInfo]:
    """Executes one primitive and does the bookkeeping of picked and lost objects."""
    env = self.config.env
    data = self._place_gripper(state.data, primitives.start_pose(action, env))
    z_before = data.qpos[self._qpos_idx[:, 2]]
    script = self.script
    data = self._simulate(data, state.in_play,
                          lambda t: primitives.target(script, action, env, t), script.length)

    z_after = data.qpos[self._qpos_idx[:, 2]]
    fingers = data.qpos[self._grip_qpos[4:]]
    holding = jnp.sum(fingers) > 0.003  # fingers stopped on something: not closed fully
    risen = state.in_play & (z_after - z_before > 0.5 * env.lift_height)
    picked = risen & holding & (action.primitive == primitives.GRASP)
    lost = state.in_play & ~picked & ~self._in_workspace(data)
    in_play = state.in_play & ~picked & ~lost
    healthy = self._health(data)
    info = StepInfo(grasp_success=jnp.any(picked), picked=jnp.sum(picked, dtype=jnp.int32),
                    lost=jnp.sum(lost, dtype=jnp.int32), left_workspace=lost, healthy=healthy)
    state = state.replace(data=self._finish(data, in_play), in_play=in_play,
                          picked=state.picked + info.picked, lost=state.lost + info.lost,
                          healthy=healthy)
    return state, info

  # ----------------------------------------------------------------------------- queries
  def object_positions(self, state: EnvState):
    """(M, 3) centre of every slot of one environment (parked slots report their parking spot)."""
    return state.data.qpos[self._qpos_idx[:, :3]]
