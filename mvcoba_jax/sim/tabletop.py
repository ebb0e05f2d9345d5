"""The batched tabletop environment: pure `reset`, `reset_from_case` and `step` over a pytree state.

Every function here works on one environment and is jittable; vmap it over B environments
(`jax.vmap(env.step)`). The physics runs in the backend `scene.backend` picks (`sim/physics.py`:
native MuJoCo on a CPU, MJX on an accelerator); nothing here depends on which. Object slots not
in play wait at their parking spots, so they never touch anything and never count.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from mvcoba_jax.sim import arrangements, cameras, occluders, physics, primitives, shapes
from mvcoba_jax.sim.config import TabletopConfig
from mvcoba_jax.sim.geometry import in_frame, quat_mul, yaw_quat
from mvcoba_jax.sim.physics import SimState
from mvcoba_jax.sim.primitives import Action
from mvcoba_jax.sim.scene import GRIPPER_PARK, Scene, build_scene

PLACEMENT_TRIES = 16  # candidate spots per object and drop layer
PLACEMENT_GAP = 0.004  # clearance between footprint circles of objects dropped in one layer
PACKED_BANK = 256  # packed arrangements a scene's `env.packed_share` drops draw from
PACKED_SEED = 90_000  # their draws: apart from validation's and the sealed suites' (generate.py)
# A grasp holds something when its fingers stop this share of the opening apart (3 mm of the
# RG2's 11 cm): a grasp that held nothing closes them fully.
HELD_SHARE = 0.003 / 0.11


def packed_bank(slot_shapes: tuple[str, ...], limit: int, size: int = PACKED_BANK,
                seed: int = PACKED_SEED) -> dict[str, jnp.ndarray]:
  """`size` packed arrangements of the training types (`arrangements.TRAINING`, in turn) on the
  scene's object slots, centred: in_play (N, M), xy (N, M, 2), yaw (N, M) rad, radius (N,) of
  the circle that holds each. A part takes a free slot of its shape, else one of a shape whose
  footprint fits inside its own (a tall box or a cylinder where a cube stood), else is left out;
  at most `limit` parts. Built once per scene, in NumPy; drops pick among them in JAX."""
  m = len(slot_shapes)
  in_play, xy = np.zeros((size, m), bool), np.zeros((size, m, 2), np.float32)
  yaw, radius = np.zeros((size, m), np.float32), np.zeros(size, np.float32)
  kinds = arrangements.TRAINING
  for n in range(size):
    parts = arrangements.TYPES[kinds[n % len(kinds)]](np.random.default_rng(seed + n))
    taken = []
    for name, x, y, part_yaw, _ in parts:
      room = arrangements.footprint(name, part_yaw)
      fits = [s for s in range(m) if not in_play[n, s] and (slot_shapes[s] == name or np.all(
          arrangements.footprint(slot_shapes[s], part_yaw) <= room + 1e-9))]
      if not fits or len(taken) == limit:
        continue
      slot = min(fits, key=lambda s: slot_shapes[s] != name)  # its own shape first
      in_play[n, slot] = True
      taken.append((slot_shapes[slot], x, y, part_yaw, 0.0, slot))
    if not taken:
      raise ValueError(f'scene.pool: no object slot fits a part of packed arrangement {n}')
    centred, radius[n] = arrangements.centred([t[:5] for t in taken])
    for (_, x, y, part_yaw, _), (*_, slot) in zip(centred, taken):
      xy[n, slot], yaw[n, slot] = (x, y), np.radians(part_yaw)
  return {k: jnp.asarray(v) for k, v in
          (('in_play', in_play), ('xy', xy), ('yaw', yaw), ('radius', radius))}


OBJECT_AT_MARGIN = 0.005  # m: a surface point seen within this of an object's box is on it


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
  sim: SimState
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
  frames: jnp.ndarray  # (F, nq) qpos at `Tabletop.frames` points of the primitive (F may be 0)


def where_envs(mask, new, old):
  """Per-environment choice between two batched pytrees: `new` where `mask` (B,) holds."""
  return jax.tree.map(
      lambda a, b: jnp.where(mask.reshape(mask.shape + (1,) * (a.ndim - 1)), a, b), new, old)


def make_backend(scene: Scene, parking: physics.Parking):
  """The backend `scene.config.backend` names, for this compiled scene (the JAX backends pin
  parked slots with the tabletop's `parking`). Each is imported when chosen: a process on the
  native backend never imports MJX, and one on MJX starts no C threads."""
  backend = physics.resolve_backend(scene.config)
  if backend == 'native':
    from mvcoba_jax.sim.native import NativePhysics  # noqa: PLC0415
    return NativePhysics(scene)
  if backend == 'warp':
    from mvcoba_jax.sim.warp_physics import WarpPhysics  # noqa: PLC0415
    return WarpPhysics(scene, parking)
  from mvcoba_jax.sim.mjx_physics import MjxPhysics  # noqa: PLC0415
  return MjxPhysics(scene, parking)


class Tabletop:
  """Static description of the environment; its methods are pure functions of the state. A
  value: tabletops of one config and number of frames are equal (and hash alike), since all
  they hold is built from those two."""

  def __init__(self, config: TabletopConfig, frames: int = 0):
    """`frames`: how many snapshots of each primitive `step` returns (for videos; 0: none)."""
    if not isinstance(config, TabletopConfig):
      raise TypeError(f'Tabletop takes the scene and episode alone (a TabletopConfig: '
                      f'config.tabletop), not a {type(config).__name__}')
    self.config = config
    self.scene = build_scene(config.scene)
    self._parking = physics.Parking(self.scene)
    self.backend = make_backend(self.scene, self._parking)
    self.camera_rays = cameras.world_rays(self.scene.mj_model, config.scene.cameras)
    idx = self.scene.index
    self.num_slots = len(idx.slot_shapes)
    if config.env.num_objects > self.num_slots:
      raise ValueError(f'env.num_objects={config.env.num_objects} exceeds the '
                       f'{self.num_slots} object slots of scene.pool')
    self.script = primitives.make_script(config.env, config.scene.timestep)
    length = self.script.length
    self.frames = tuple(int(round((i + 1) * length / frames)) - 1 for i in range(frames))
    self._qpos_idx = self._parking.qpos_idx
    self._grip_qpos = jnp.asarray(idx.gripper_qpos)
    self._grip_qvel = jnp.asarray(idx.gripper_qvel)
    self._park_qpos = self._parking.park_qpos
    opened = primitives.finger_open(config.scene.gripper)
    self._gripper_park = jnp.array(GRIPPER_PARK + (0.0, opened, opened), jnp.float32)
    slot_shapes = [shapes.shape(s) for s in idx.slot_shapes]
    self._rest_quat = jnp.asarray([s.rest_quat for s in slot_shapes], jnp.float32)
    self._rest_half_height = jnp.asarray([0.5 * s.rest_extent[2] for s in slot_shapes],
                                         jnp.float32)
    self._half_extent = jnp.asarray([0.5 * np.asarray(s.extent) for s in slot_shapes],
                                    jnp.float32)
    self._radius = jnp.asarray([shapes.footprint_radius(s.name) for s in slot_shapes],
                               jnp.float32)
    self._bounding_radius = jnp.asarray([0.5 * np.linalg.norm(s.rest_extent)
                                         for s in slot_shapes], jnp.float32)
    if config.env.packed_share > 0:
      self._bank = packed_bank(idx.slot_shapes, config.env.num_objects)

  def __eq__(self, other) -> bool:
    return type(other) is type(self) and (self.config, self.frames) == (other.config,
                                                                         other.frames)

  def __hash__(self) -> int:
    return hash((self.config, self.frames))

  # ----------------------------------------------------------------------------- physics core
  def _place_gripper(self, sim: SimState, pose) -> SimState:
    """Puts the gripper at `pose` (x, y, z, yaw, fingers), at rest."""
    return sim.replace(qpos=sim.qpos.at[self._grip_qpos].set(pose),
                       qvel=sim.qvel.at[self._grip_qvel].set(0.0))

  def _simulate(self, sim: SimState, in_play, ctrl, frames: tuple[int, ...] = (), steps=None):
    """Steps through the first `steps` actuator targets of `ctrl` (T, 6) (all if None); also
    whether the physics stayed sound, and qpos after each step of `frames`."""
    sim, ok, at = self.backend.simulate(sim, ~in_play, ctrl, frames, steps)
    return sim, ok & self._health(sim), at

  def _health(self, sim: SimState):
    finite = jnp.all(jnp.isfinite(sim.qpos)) & jnp.all(jnp.isfinite(sim.qvel))
    return finite & (jnp.max(jnp.abs(sim.qvel)) < self.config.env.max_qvel)

  def _in_workspace(self, sim: SimState):
    pos = sim.qpos[self._qpos_idx[:, :3]]
    h = self.config.scene.workspace_half
    return (jnp.abs(pos[:, 0]) <= h) & (jnp.abs(pos[:, 1]) <= h) & (pos[:, 2] > -0.05)

  def _finish(self, sim: SimState, in_play) -> SimState:
    """Parks the gripper and the objects out of play."""
    return self._parking.pin(self._place_gripper(sim, self._gripper_park), ~in_play)

  # ----------------------------------------------------------------------------- reset
  def sample_layout(self, key) -> Layout:
    """A random drop of `env.num_objects` objects: greedy non-overlapping spots in stacked layers.

    Objects that do not fit beside the others go to a layer `layer_height` higher and fall onto
    the pile while the scene settles, as sequential drops would. `env.drop='heap'` drops them in
    a random 3-D orientation (spaced by the sphere that bounds each) into the central square of
    half side `env.heap_half`, where few fit beside each other, so they land on each other.
    """
    env, m = self.config.env, self.num_slots
    n = env.num_objects
    heap = env.drop == 'heap'
    layers = n if heap else 1 + n // 4
    k_perm, k_place, k_yaw, k_color = jax.random.split(key, 4)
    order = jax.random.permutation(k_perm, m)
    in_play = jnp.zeros(m, bool).at[order[:n]].set(True)
    lim = env.heap_half if heap else self.config.scene.workspace_half - env.drop_margin
    radius = self._bounding_radius if heap else self._radius
    cands = jax.random.uniform(k_place, (n, layers * PLACEMENT_TRIES, 2), minval=-lim, maxval=lim)
    cand_layer = jnp.repeat(jnp.arange(layers), PLACEMENT_TRIES)

    def place(i, carry):
      xy, layer, placed = carry
      s = order[i]
      dist = jnp.linalg.norm(cands[i][:, None, :] - xy[None], axis=-1)
      clash = placed[None] & (layer[None] == cand_layer[:, None]) & (
          dist < radius[s] + radius[None] + PLACEMENT_GAP)
      free = ~jnp.any(clash, axis=1)
      j = jnp.where(jnp.any(free), jnp.argmax(free), free.shape[0] - 1)
      return xy.at[s].set(cands[i, j]), layer.at[s].set(cand_layer[j]), placed.at[s].set(True)

    xy, layer, _ = jax.lax.fori_loop(
        0, n, place, (jnp.zeros((m, 2)), jnp.zeros(m, jnp.int32), jnp.zeros(m, bool)))
    if heap:  # each layer clears the one below, whatever the orientations
      z = self._bounding_radius + 0.002 + layer * jnp.maximum(
          env.layer_height, 2 * jnp.max(radius) + PLACEMENT_GAP)
    else:
      z = self._rest_half_height + 0.002 + layer * env.layer_height
    pos = jnp.where(in_play[:, None], jnp.concatenate([xy, z[:, None]], axis=1),
                    self._park_qpos[:, :3])
    if heap:  # uniform over rotations: a normalised 4-D Gaussian
      quat = jax.random.normal(k_yaw, (m, 4))
      quat = quat / jnp.linalg.norm(quat, axis=1, keepdims=True)
    else:
      quat = quat_mul(yaw_quat(jax.random.uniform(k_yaw, (m,), maxval=2 * jnp.pi)),
                      self._rest_quat)
    if env.packed_share > 0:
      k_packed, k_share = jax.random.split(jax.random.fold_in(key, 2))
      packed = jax.random.uniform(k_share) < env.packed_share
      packed_in_play, packed_pos, packed_quat = self._packed(k_packed)
      in_play = jnp.where(packed, packed_in_play, in_play)
      pos = jnp.where(packed, packed_pos, pos)
      quat = jnp.where(packed, packed_quat, quat)
    color = jnp.asarray(shapes.COLORS)[jax.random.permutation(k_color, jnp.arange(m) % 10)]
    occluder_pos, occluder_quat = self.drawn_occluders(jax.random.fold_in(key, 1))
    return Layout(in_play=in_play, pos=pos, quat=quat, color=color,
                  occluder_pos=occluder_pos, occluder_quat=occluder_quat)

  def _packed(self, key):
    """(in_play, pos, quat) of an `env.packed_share` drop: one arrangement of `packed_bank`,
    turned by a drawn yaw about a drawn centre that keeps it inside the workspace less
    `env.drop_margin`."""
    bank = self._bank
    k_pick, k_yaw, k_centre = jax.random.split(key, 3)
    pick = jax.random.randint(k_pick, (), 0, bank['in_play'].shape[0])
    in_play, xy, part_yaw = bank['in_play'][pick], bank['xy'][pick], bank['yaw'][pick]
    yaw = jax.random.uniform(k_yaw, (), maxval=2 * jnp.pi)
    c, s = jnp.cos(yaw), jnp.sin(yaw)
    turned = jnp.stack([c * xy[:, 0] - s * xy[:, 1], s * xy[:, 0] + c * xy[:, 1]], 1)
    room = jnp.maximum(self.config.scene.workspace_half - self.config.env.drop_margin
                       - bank['radius'][pick], 0.0)
    centre = jax.random.uniform(k_centre, (2,), minval=-room, maxval=room)
    z = self._rest_half_height + 0.002
    pos = jnp.where(in_play[:, None], jnp.concatenate([turned + centre, z[:, None]], 1),
                    self._park_qpos[:, :3])
    quat = quat_mul(yaw_quat(yaw + part_yaw), self._rest_quat)
    return in_play, pos, quat

  def drawn_occluders(self, key):
    """Occluder poses of a random drop: with probability `env.occluded_share`, one occluder
    before a drawn camera, slot 0 (whole) or, with a second slot, as often slot 1 (part), its
    pose drawn from `occluders.TRAINING`, apart from every test case's; every other slot parked."""
    pos, quat = self.parked_occluders()
    share = self.config.env.occluded_share
    if share == 0:
      return pos, quat
    k_on, k_pose = jax.random.split(key)
    cameras_xy = jnp.asarray([c.pos[:2] for c in self.config.scene.cameras], jnp.float32)
    _, part, (x, y, z, yaw) = occluders.drawn(occluders.TRAINING, k_pose, cameras_xy,
                                              len(self.config.scene.occluders) > 1)
    slot = part.astype(jnp.int32)
    on = jax.random.uniform(k_on) < share
    pos = pos.at[slot].set(jnp.where(on, jnp.stack([x, y, z]), pos[slot]))
    quat = quat.at[slot].set(jnp.where(on, yaw_quat(yaw), quat[slot]))
    return pos, quat

  def parked_occluders(self):
    """Poses of the occluder slots when a layout uses none of them: at their model positions."""
    sim, mocap = physics.initial_state(self.scene), self.scene.index.occluder_mocap
    return sim.mocap_pos[mocap], sim.mocap_quat[mocap]

  def reset(self, key) -> EnvState:
    """Drops `env.num_objects` random objects and lets them settle."""
    return self.settle(self.drop(key))

  def drop(self, key) -> EnvState:
    """`env.num_objects` random objects at their drop spots, before any physics (`reset`
    settles them)."""
    key, k_layout = jax.random.split(key)
    return self.place(self.sample_layout(k_layout), key)

  def place(self, layout: Layout, key=None) -> EnvState:
    """The objects of `layout` exactly where it puts them, without physics (for pictures)."""
    if key is None:
      key = jax.random.PRNGKey(0)
    sim = physics.initial_state(self.scene)
    qpos = sim.qpos.at[self._qpos_idx].set(
        jnp.where(layout.in_play[:, None], jnp.concatenate([layout.pos, layout.quat], 1),
                  self._park_qpos))
    mocap = self.scene.index.occluder_mocap
    sim = sim.replace(qpos=qpos, mocap_pos=sim.mocap_pos.at[mocap].set(layout.occluder_pos),
                      mocap_quat=sim.mocap_quat.at[mocap].set(layout.occluder_quat))
    return EnvState(sim=self._finish(sim, layout.in_play), in_play=layout.in_play,
                    color=layout.color, picked=jnp.int32(0), lost=jnp.int32(0),
                    healthy=self._health(sim), health_resets=jnp.int32(0), key=key)

  def reset_from_case(self, layout: Layout, key=None) -> EnvState:
    """Places the objects of `layout` (a test case or a random drop) and lets them settle."""
    return self.settle(self.place(layout, key))

  def settle(self, state: EnvState, steps: int | None = None) -> EnvState:
    """`state` after `steps` physics steps (`env.settle_steps` if None) with the gripper parked,
    the objects coming to rest; those that leave the workspace leave play uncounted (a drop
    that lands off the table is not a loss)."""
    steps = self.config.env.settle_steps if steps is None else steps
    sim, healthy, _ = self._simulate(state.sim, state.in_play, self._hold(steps))
    return self._settled(state, sim, healthy)

  def _hold(self, steps: int):
    return jnp.broadcast_to(self._gripper_park, (steps, 6))

  def _settled(self, state: EnvState, sim: SimState, healthy) -> EnvState:
    in_play = state.in_play & self._in_workspace(sim)
    return state.replace(sim=self._finish(sim, in_play), in_play=in_play, healthy=healthy)

  # ----------------------------------------------------------------------------- step
  def step(self, state: EnvState, action: Action) -> tuple[EnvState, StepInfo]:
    """Executes one primitive and does the bookkeeping of picked and lost objects."""
    sim, ctrl = self._begin(state, action)
    after, healthy, frames = self._simulate(sim, state.in_play, ctrl, self.frames)
    return self._outcome(state, action, sim, after, healthy, frames)

  def step_and_settle(self, state: EnvState, action: Action, drop: EnvState, settle
                      ) -> tuple[EnvState, StepInfo, EnvState]:
    """`step(state, action)` and, when `settle` (a bool shared by the batch), `settle(drop)`,
    in one physics loop run twice: the primitive's steps, then the settling's (none without
    `settle`, and `drop` comes back as it went). A compiled program holding both pays for one
    traced physics loop instead of two (docs/results/mjx-compile.md)."""
    sim, ctrl = self._begin(state, action)
    hold = self._hold(self.config.env.settle_steps)
    length = max(ctrl.shape[0], hold.shape[0])
    pad = lambda c: jnp.concatenate([c, jnp.zeros((length - c.shape[0], 6))])  # rows not run
    phases = (jax.tree.map(lambda *x: jnp.stack(x), sim, drop.sim),
              jnp.stack([state.in_play, drop.in_play]), jnp.stack([pad(ctrl), pad(hold)]),
              jnp.stack([jnp.int32(ctrl.shape[0]),
                         jnp.where(settle, hold.shape[0], 0).astype(jnp.int32)]))

    def phase(_, inputs):
      start, in_play, targets, steps = inputs
      return None, self._simulate(start, in_play, targets, self.frames, steps)

    _, (sims, ok, frames) = jax.lax.scan(phase, None, phases)
    after, settled = (jax.tree.map(lambda x, i=i: x[i], sims) for i in range(2))
    state, info = self._outcome(state, action, sim, after, ok[0], frames[0])
    drop = jax.tree.map(lambda new, old: jnp.where(settle, new, old),
                        self._settled(drop, settled, ok[1]), drop)
    return state, info, drop

  def _begin(self, state: EnvState, action: Action):
    """The gripper at the primitive's start pose, and its actuator targets (T, 6)."""
    env, scene = self.config.env, self.config.scene
    sim = self._place_gripper(state.sim, primitives.start_pose(action, env, scene.gripper))
    ctrl = jax.vmap(lambda t: primitives.target(self.script, action, env, scene.gripper,
                                                scene.workspace_half, t))(
        jnp.arange(self.script.length))
    return sim, ctrl

  def _outcome(self, state: EnvState, action: Action, before: SimState, sim: SimState, healthy,
               frames) -> tuple[EnvState, StepInfo]:
    """The bookkeeping of a primitive run from `before` to `sim`: picked and lost objects."""
    env = self.config.env
    z_before = before.qpos[self._qpos_idx[:, 2]]
    z_after = sim.qpos[self._qpos_idx[:, 2]]
    fingers = sim.qpos[self._grip_qpos[4:]]
    # Fingers stopped on something, not closed fully: apart by a share of the opening.
    holding = jnp.sum(fingers) > HELD_SHARE * self.config.scene.gripper.max_opening
    risen = state.in_play & (z_after - z_before > 0.5 * env.lift_height)
    picked = risen & holding & (action.primitive == primitives.GRASP)
    lost = state.in_play & ~picked & ~self._in_workspace(sim)
    in_play = state.in_play & ~picked & ~lost
    info = StepInfo(grasp_success=jnp.any(picked), picked=jnp.sum(picked, dtype=jnp.int32),
                    lost=jnp.sum(lost, dtype=jnp.int32), left_workspace=lost, healthy=healthy,
                    frames=frames)
    state = state.replace(sim=self._finish(sim, in_play), in_play=in_play,
                          picked=state.picked + info.picked, lost=state.lost + info.lost,
                          healthy=healthy)
    return state, info

  def emptied(self, state: EnvState) -> EnvState:
    """`state` with every object taken off the table to its parking spot. A step of an empty
    tabletop costs a fraction of a cluttered one's (no contacts to solve): what a batch steps
    in place of tabletops whose results it no longer counts."""
    none = jnp.zeros_like(state.in_play)
    return state.replace(sim=self._finish(state.sim, none), in_play=none)

  # ----------------------------------------------------------------------------- queries
  def object_positions(self, state: EnvState):
    """(M, 3) centre of every slot of one environment (parked slots report their parking spot)."""
    return state.sim.qpos[self._qpos_idx[:, :3]]

  def object_at(self, state: EnvState, point):
    """The slot of the object in play under `point` (x, y, z on the surface the cameras saw) of
    one environment, -1 for none: the topmost whose bounding box, grown by OBJECT_AT_MARGIN on
    each side, holds the point (its own frame: a box lying askew on a heap is found as it lies).
    What an evaluation counts a failed grasp against, per shape."""
    pose = state.sim.qpos[self._qpos_idx]
    local = in_frame(pose[:, 3:], jnp.asarray(point, jnp.float32) - pose[:, :3])
    inside = state.in_play & jnp.all(jnp.abs(local) <= self._half_extent + OBJECT_AT_MARGIN,
                                     axis=-1)
    return jnp.where(jnp.any(inside), jnp.argmax(jnp.where(inside, pose[:, 2], -jnp.inf)), -1)
