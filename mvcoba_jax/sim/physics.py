"""Physics backends behind one interface: native MuJoCo (C, host threads), MJX's JAX
implementation, and MuJoCo Warp with its batch renderer (NVIDIA GPUs).

A backend steps a batch of tabletops through a control sequence and casts the cameras' rays, both
as pure functions of a compact `SimState` that are jittable and vmappable; the environment above
never branches on which backend runs. `scene.backend='auto'` is the backend measured fastest on
each kind of device (`resolve_backend`).

Out-of-play object slots come in at their parking spots (the environment puts them there after
every call) and both backends keep them there: MJX pins their pose on every step; native MuJoCo
switches on their gravity compensation, so they float at rest, touch nothing and cost nothing.
"""
from __future__ import annotations

import os

import jax.numpy as jnp
import numpy as np
from flax import struct

from mvcoba_jax.sim.config import SceneConfig
from mvcoba_jax.sim.scene import GRIPPER_GROUP, Scene, park_position

CAMERA_GROUPS = tuple(int(g != GRIPPER_GROUP) for g in range(6))


@struct.dataclass
class SimState:
  """What the next physics call needs of one tabletop (float32; velocities at rest are ~0)."""
  qpos: jnp.ndarray  # (nq,)
  qvel: jnp.ndarray  # (nv,)
  mocap_pos: jnp.ndarray  # (nmocap, 3): the occluders
  mocap_quat: jnp.ndarray  # (nmocap, 4)


def resolve_backend(scene: SceneConfig) -> str:
  """The backend `scene.backend` names; 'auto' is native MuJoCo on every device: on the 2-core
  CPU it outruns MJX 80-120x and Warp's CPU device (`benchmarks/physics.py`), and on the one
  accelerator host measured (an H200 with 16 cores, docs/results/gpu-h200.md) it outran MJX's
  JAX implementation at 64 to 4096 tabletops. Warp is chosen by name (the `gpu` preset) until
  a measurement on an accelerator says it is faster."""
  return 'native' if scene.backend == 'auto' else scene.backend


FORCE_WARP_CPU = 'MVCOBA_JAX_WARP_CPU'  # set to 1: run Warp on its CPU device all the same


def device_problem(scene: SceneConfig) -> str | None:
  """Why `scene` should not run on this machine, in one line, or None: Warp named where it finds
  no CUDA device (it would fall back to its CPU device, which trains far slower than native
  MuJoCo on a CPU: docs/results/warp.md), unless the environment variable
  `FORCE_WARP_CPU` is 1 (the tests run Warp on the CPU on purpose)."""
  if resolve_backend(scene) != 'warp' or os.environ.get(FORCE_WARP_CPU) == '1':
    return None
  import warp  # noqa: PLC0415 (the gpu extra; only a Warp run needs it)
  if warp.is_cuda_available():
    return None
  return ('scene.backend=warp (the gpu preset): Warp finds no CUDA device here and would run on '
          'its CPU device, far slower than native MuJoCo; on a CPU use --config default, or set '
          f'{FORCE_WARP_CPU}=1 to run Warp on the CPU all the same')


def initial_state(scene: Scene) -> SimState:
  """The compiled model's own pose of everything: objects parked, gripper and occluders home."""
  m = scene.mj_model
  bodies = np.flatnonzero(m.body_mocapid >= 0)[np.argsort(m.body_mocapid[m.body_mocapid >= 0])]
  return SimState(qpos=jnp.asarray(m.qpos0, jnp.float32), qvel=jnp.zeros(m.nv, jnp.float32),
                  mocap_pos=jnp.asarray(m.body_pos[bodies], jnp.float32).reshape(-1, 3),
                  mocap_quat=jnp.asarray(m.body_quat[bodies], jnp.float32).reshape(-1, 4))


def parked_slot_qpos(scene: Scene) -> np.ndarray:
  """(M, 7) free-joint pose of every object slot at its parking spot."""
  return np.array([park_position(i) + (1.0, 0.0, 0.0, 0.0)
                   for i in range(len(scene.index.slot_shapes))], np.float32)


class Parking:
  """Puts out-of-play object slots at their parking spots, at rest, in JAX."""

  def __init__(self, scene: Scene):
    idx = scene.index
    self.qpos_idx = jnp.asarray(idx.slot_qpos[:, None] + np.arange(7))
    self.qvel_idx = jnp.asarray(idx.slot_qvel[:, None] + np.arange(6))
    self.park_qpos = jnp.asarray(parked_slot_qpos(scene))

  def pin(self, state, parked):
    """`state` (a SimState or an mjx.Data) with the `parked` (M,) slots parked."""
    qpos = state.qpos.at[self.qpos_idx].set(
        jnp.where(parked[:, None], self.park_qpos, state.qpos[self.qpos_idx]))
    qvel = state.qvel.at[self.qvel_idx].set(
        jnp.where(parked[:, None], 0.0, state.qvel[self.qvel_idx]))
    return state.replace(qpos=qpos, qvel=qvel)
