"""Native MuJoCo physics and ray casting for CPUs, called from inside jitted, vmapped JAX code.

Each function is one `jax.pure_callback` with `vmap_method='broadcast_all'`: however many vmaps
wrap it, the host gets the whole batch in one call and hands it to `mujoco.batch.Batch`, which
steps (or casts rays for) every tabletop on a pool of C threads. Batch results are bit-identical
at any thread count. The host side is pure (each call loads every state it uses from its inputs)
and lends each call a Batch of its size that no other call holds, so the shards of several devices
can call it at once. (Not thread-local Batches: XLA runs callbacks on its own threads, whose Python
thread state, thread-locals included, is torn down after every call.)

Health: a MuJoCo warning (bad qpos/qvel/qacc/ctrl, full contact arena) or error during a call
makes that tabletop report not ok; the caller marks it unhealthy. Nothing is raised and the other
tabletops run to completion.
"""
from __future__ import annotations

import contextlib
import functools
import math
import os
import threading

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from mujoco import batch as mjbatch

from mvcoba_jax.sim.physics import CAMERA_GROUPS, SimState
from mvcoba_jax.sim.scene import Scene


def default_threads() -> int:
  """The cores this process may run on."""
  return len(os.sched_getaffinity(0))


class NativePhysics:
  """MuJoCo's C engine on a thread pool: the path for CPUs."""

  name = 'native'
  traced = False  # a host call: a program holds only the call

  def __init__(self, scene: Scene):
    m = scene.mj_model
    self._model = m
    self._threads = scene.config.native_threads or default_threads()
    self._slot_bodies = np.array([mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f'obj{i}')
                                  for i in range(len(scene.index.slot_shapes))])
    self._gravcomp = m.body_gravcomp.copy()
    self._free: dict[int, list[mjbatch.Batch]] = {}  # idle Batches by size
    self._lock = threading.Lock()

  @contextlib.contextmanager
  def _batch(self, n: int):
    """A Batch of n simulations that no other call uses meanwhile (a Batch serves one at once)."""
    with self._lock:
      free = self._free.setdefault(n, [])
      b = free.pop() if free else None
    if b is None:
      b = mjbatch.Batch(self._model, n, nthread=min(self._threads, n))
    try:
      yield b
    finally:
      with self._lock:
        self._free[n].append(b)

  @staticmethod
  def _load(b: mjbatch.Batch, qpos, mocap_pos, mocap_quat, qvel=None) -> None:
    """The state rows of `b` set to the given states (everything else zero, warm start too)."""
    n = b.nsim
    b.state[:] = 0.0
    b.qpos[:] = qpos.reshape(n, -1)
    if qvel is not None:
      b.qvel[:] = qvel.reshape(n, -1)
    b.mocap_pos[:] = mocap_pos.reshape(b.mocap_pos.shape)
    b.mocap_quat[:] = mocap_quat.reshape(b.mocap_quat.shape)

  def _simulate_host(self, frames: tuple[int, ...], *arrays):
    # JAX hands over jax.Arrays on the CPU: viewed as NumPy (no copy), no JAX op runs in here.
    qpos, qvel, mocap_pos, mocap_quat, parked, ctrl, steps = (np.asarray(a) for a in arrays)
    lead = qpos.shape[:-1]
    n = math.prod(lead)
    steps = int(np.max(steps, initial=0))  # one count for the batch
    if steps == 0:
      return qpos.copy(), qvel.copy(), np.ones(lead, bool), np.repeat(
          qpos[..., None, :], len(frames), axis=-2)
    parked = parked.reshape(n, -1)
    ok = np.ones(n, bool)
    with self._batch(n) as b:
      self._load(b, qpos, mocap_pos, mocap_quat, qvel)
      gravcomp = b.expand('body_gravcomp')
      gravcomp[:] = self._gravcomp
      gravcomp[:, self._slot_bodies] = parked
      b.warning[:] = 0
      record = {}
      try:
        run = np.ascontiguousarray(ctrl.reshape(n, ctrl.shape[-2], -1)[:, :steps])
        record = b.rollout(steps, run, record=('qpos',) if frames else ())
      except mjbatch.SimulationError as error:
        ok[error.ids] = False
      ok &= ~np.any(b.warning[..., 1] > 0, axis=-1)
      qpos_out = b.qpos.astype(np.float32).reshape(lead + qpos.shape[-1:])
      qvel_out = b.qvel.astype(np.float32).reshape(lead + qvel.shape[-1:])
      if 'qpos' in record:
        at = record['qpos'][:, np.minimum(frames, steps - 1)]
      else:  # no pictures asked for, or the call failed: where it stopped
        at = np.repeat(b.qpos[:, None], len(frames), axis=1)
    return qpos_out, qvel_out, ok.reshape(lead), at.astype(np.float32).reshape(
        lead + (len(frames), qpos.shape[-1]))

  def simulate(self, sim: SimState, parked, ctrl, frames: tuple[int, ...] = (), steps=None):
    """Steps one tabletop through the first `steps` rows of `ctrl` (T, nu) (all if None; vmap
    it: the host gets the batch in one call); returns the state, whether MuJoCo ran it without a
    warning or an error, and qpos after each step of `frames` (F, nq) (recorded only when
    asked: a few pictures of a primitive)."""
    steps = jnp.int32(ctrl.shape[-2]) if steps is None else steps
    shapes = (jax.ShapeDtypeStruct(sim.qpos.shape, jnp.float32),
              jax.ShapeDtypeStruct(sim.qvel.shape, jnp.float32),
              jax.ShapeDtypeStruct((), jnp.bool_),
              jax.ShapeDtypeStruct((len(frames),) + sim.qpos.shape, jnp.float32))
    qpos, qvel, ok, at = jax.pure_callback(
        functools.partial(self._simulate_host, tuple(frames)), shapes, sim.qpos, sim.qvel,
        sim.mocap_pos, sim.mocap_quat, parked, ctrl, steps, vmap_method='broadcast_all')
    return sim.replace(qpos=qpos, qvel=qvel), ok, at

  def _cast_host(self, origins, directions, *arrays):
    qpos, mocap_pos, mocap_quat = (np.asarray(a) for a in arrays)
    lead = qpos.shape[:-1]
    n = math.prod(lead)
    with self._batch(n) as b:
      self._load(b, qpos, mocap_pos, mocap_quat)
      try:
        dist, geom = b.ray(origins, directions, geomgroup=CAMERA_GROUPS)
      except mjbatch.SimulationError as error:  # a state MuJoCo rejects: all its rays miss
        good = np.setdiff1d(np.arange(n), error.ids)
        dist, geom = np.full((n, len(origins)), -1.0), np.full((n, len(origins)), -1, np.int32)
        dist[good], geom[good] = b.ray(origins, directions, geomgroup=CAMERA_GROUPS, ids=good)
    return (dist.astype(np.float32).reshape(lead + dist.shape[-1:]),
            geom.astype(np.int32).reshape(lead + geom.shape[-1:]))

  def cast(self, sim: SimState, origins: np.ndarray, directions: np.ndarray):
    """Distance (P,) and geom id (P,) of every ray of one tabletop; -1 for a miss."""
    p = origins.shape[0]
    shapes = (jax.ShapeDtypeStruct((p,), jnp.float32), jax.ShapeDtypeStruct((p,), jnp.int32))
    host = lambda *state: self._cast_host(origins, directions, *state)
    return jax.pure_callback(host, shapes, sim.qpos, sim.mocap_pos, sim.mocap_quat,
                             vmap_method='broadcast_all')
