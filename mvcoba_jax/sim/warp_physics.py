"""The Warp backend: MuJoCo Warp behind MJX's API (`impl='warp'`) steps every tabletop as one
world of a batch, and its batch ray-tracing renderer draws both cameras of every world in one
launch, all inside the jitted program (the path for NVIDIA GPUs; on a CPU Warp runs too, slowly,
which is how CI checks it against native MuJoCo).

Warp sizes its buffers by the number of worlds: the contact arena (`naconmax`, shared by the
batch) and the render context exist per batch size. So each function here is written over a
whole batch and wrapped by `batched`, which makes it a per-tabletop function that vmaps like any
other: however many vmaps wrap it, it runs once on all tabletops flattened into one axis, and a
batch size met for the first time gets its buffers then (at trace time).

Health: a world whose contacts or constraints overflow the arena is reported not ok (the
tabletop above resets it and counts it); MuJoCo Warp raises no warnings, and the caller checks
finiteness as on the other backends.
"""
from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import warp

# Warp prints its start and every module load on stdout, where scripts print JSON.
warp.config.log_level = warp.LOG_WARNING
from mujoco import mjx  # noqa: E402

from mvcoba_jax.sim import cameras  # noqa: E402
from mvcoba_jax.sim.mjx_physics import stepped  # noqa: E402
from mvcoba_jax.sim.physics import CAMERA_GROUPS, Parking, SimState  # noqa: E402
from mvcoba_jax.sim.scene import Scene  # noqa: E402

CONSTRAINT_ROWS = 4  # per contact: a pyramidal cone of condim 3 has 2 * (3 - 1) rows
EXTRA_ROWS = 16  # joint limits and the like, per world


# mujoco-mjx 4.0 keeps what only its Warp implementation has (the overflow warning switch, the
# rows and contacts a step filled) in the private `_impl` of its Model and Data, with no public
# accessor: these two functions are the only places this project reads or writes it.
def _quiet(model: mjx.Model) -> mjx.Model:
  """`model` with Warp's overflow messages off (it prints them on stdout, where scripts print
  JSON; overflows are caught from the fill counts and reported not ok instead)."""
  impl = model.opt._impl  # pylint: disable=protected-access
  return model.replace(opt=model.opt.replace(_impl=impl.replace(warn_overflow=0)))


def _filled(data: mjx.Data):
  """(constraint rows, contacts) the last step of this world filled."""
  impl = data._impl  # pylint: disable=protected-access
  return impl.nefc, impl.nacon


def batched(fn):
  """A per-example function from `fn`, a function of arrays with a leading batch axis (and of
  them only): under any number of vmaps `fn` is called once, on every example flattened into one
  leading axis; unbatched arguments are broadcast. Called on one example, it is a batch of one."""

  def broadcast(axis_size, in_batched, args):
    return [a if b else jnp.broadcast_to(a, (axis_size,) + a.shape)
            for a, b in zip(args, in_batched)]

  @jax.custom_batching.custom_vmap
  def many(*args):
    return fn(*args)

  @many.def_vmap
  def many_rule(axis_size, in_batched, *args):  # a vmap over batches: one larger batch
    args = broadcast(axis_size, in_batched, args)
    out = many(*(a.reshape((-1,) + a.shape[2:]) for a in args))
    out = jax.tree.map(lambda x: x.reshape((axis_size, -1) + x.shape[1:]), out)
    return out, jax.tree.map(lambda _: True, out)

  @jax.custom_batching.custom_vmap
  def one(*args):
    return jax.tree.map(lambda x: x[0], many(*(a[None] for a in args)))

  @one.def_vmap
  def one_rule(axis_size, in_batched, *args):
    args = broadcast(axis_size, in_batched, args)
    out = many(*args)
    return out, jax.tree.map(lambda _: True, out)

  return one


class WarpPhysics:
  """MuJoCo Warp through MJX and its batch renderer: one world per tabletop."""

  name = 'warp'
  traced = False  # Warp's kernels, compiled by Warp: XLA compiles only the calls to them

  def __init__(self, scene: Scene, parking: Parking):
    m = scene.mj_model
    self._mj_model = m
    self.model = _quiet(mjx.put_model(m, impl='warp'))
    self._parking = parking
    self._cameras = scene.config.cameras
    self._contacts = scene.config.max_contact_points
    self._rows = CONSTRAINT_ROWS * self._contacts + EXTRA_ROWS  # each world's constraint rows
    self._origins, self._directions = cameras.world_rays(m, self._cameras)
    self._templates: dict[int, mjx.Data] = {}
    self._contexts: dict[int, object] = {}
    self._groups = [g for g, on in enumerate(CAMERA_GROUPS) if on]
    self._cast = batched(self._cast_batch)
    self._simulators: dict[tuple[int, ...], object] = {}  # frames -> its batched simulate

  def _arena(self, n: int) -> int:
    """Contacts the shared arena of `n` worlds holds."""
    return n * self._contacts

  def _template(self, n: int) -> mjx.Data:
    """Data of one world whose shared buffers hold `n` worlds' contacts (made once per n)."""
    if n not in self._templates:
      with jax.ensure_compile_time_eval():  # made while a program traces: concrete, not traced
        data = mjx.make_data(self._mj_model, impl='warp', naconmax=self._arena(n),
                             njmax=self._rows)
      # The cameras are fixed in the world: their poses once, from MuJoCo (MJX's camlight is
      # not implemented on Warp).
      host = mujoco.MjData(self._mj_model)
      mujoco.mj_forward(self._mj_model, host)
      self._templates[n] = data.replace(
          cam_xpos=host.cam_xpos.astype(np.float32),
          cam_xmat=host.cam_xmat.reshape(-1, 3, 3).astype(np.float32))
    return self._templates[n]

  def _context(self, n: int):
    """The render context of `n` worlds, both cameras at their configured resolution, depth and
    segmentation only, the gripper's geom group left out (made once per n)."""
    if n not in self._contexts:  # kept: its buffers live as long as the context object
      self._contexts[n] = mjx.create_render_context(
          self._mj_model, n, cam_res=[(c.width, c.height) for c in self._cameras],
          render_rgb=False, render_depth=True, render_seg=True, use_textures=False,
          enabled_geom_groups=self._groups)
    return self._contexts[n].pytree()

  def _data(self, template: mjx.Data, qpos, qvel, mocap_pos, mocap_quat) -> mjx.Data:
    return template.replace(qpos=qpos, qvel=qvel, mocap_pos=mocap_pos, mocap_quat=mocap_quat)

  def simulate(self, sim: SimState, parked, ctrl, frames: tuple[int, ...] = (), steps=None):
    """Steps one tabletop through the first `steps` rows of `ctrl` (T, nu) (all if None; vmap
    it: Warp gets the batch in one program); returns the state, whether its contacts fitted the
    arena, and qpos after each step of `frames` (F, nq)."""
    frames = tuple(frames)
    if frames not in self._simulators:  # one wrapper per frames, not one per call
      self._simulators[frames] = batched(functools.partial(self._simulate_batch, frames))
    run = self._simulators[frames]
    steps = jnp.int32(ctrl.shape[-2]) if steps is None else steps
    qpos, qvel, ok, at = run(sim.qpos, sim.qvel, sim.mocap_pos, sim.mocap_quat, parked, ctrl,
                             steps)
    return sim.replace(qpos=qpos, qvel=qvel), ok, at

  def _simulate_batch(self, frames, qpos, qvel, mocap_pos, mocap_quat, parked, ctrl, steps):
    template = self._template(qpos.shape[0])
    pin = self._parking.pin
    steps = jnp.max(steps)  # one count for the batch (`batched` hands it to every world)

    def world(qp, qv, mp, mq, pk, c):
      d, at, (nefc, nacon) = stepped(self.model, self._data(template, qp, qv, mp, mq), c, pin,
                                     pk, frames, steps, _filled)
      return d.qpos, d.qvel, jnp.max(nefc), jnp.max(nacon), at

    qpos, qvel, nefc, nacon, at = jax.vmap(world)(qpos, qvel, mocap_pos, mocap_quat, parked, ctrl)
    ok = (nefc < self._rows) & (nacon < self._arena(qpos.shape[0]))
    return qpos, qvel, ok, at

  def cast(self, sim: SimState, origins: np.ndarray, directions: np.ndarray):
    """Distance (P,) and geom id (P,) of every ray of one tabletop, -1 for a miss: the cameras'
    rays only (`cameras.world_rays`), which the renderer casts itself."""
    if not (np.array_equal(origins, self._origins) and np.array_equal(directions,
                                                                       self._directions)):
      raise ValueError('the warp backend casts the cameras\' rays only')
    return self._cast(sim.qpos, sim.mocap_pos, sim.mocap_quat)

  def _cast_batch(self, qpos, mocap_pos, mocap_quat):
    n = qpos.shape[0]
    template, context = self._template(n), self._context(n)

    def pose(qp, mp, mq):
      d = self._data(template, qp, jnp.zeros(self._mj_model.nv, jnp.float32), mp, mq)
      return mjx.kinematics(self.model, d)

    d = jax.vmap(pose)(qpos, mocap_pos, mocap_quat)
    d = jax.vmap(lambda d: mjx.refit_bvh(self.model, d, context))(d)
    _, depth, seg, _ = jax.vmap(lambda d: mjx.render_with_segmentation(self.model, d, context))(d)
    geom = jnp.where(seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM), seg[..., 0], -1)
    along = jnp.asarray(self._along_axis())
    dist = jnp.where(geom >= 0, depth / along, -1.0)
    return dist.astype(jnp.float32), geom.astype(jnp.int32)

  def _along_axis(self) -> np.ndarray:
    """(P,) cosine of each camera pixel's ray with its camera's optical axis: planar depth over
    it is the distance along the ray."""
    return np.concatenate([-cameras.pixel_rays(c).reshape(-1, 3)[:, 2] for c in self._cameras])
