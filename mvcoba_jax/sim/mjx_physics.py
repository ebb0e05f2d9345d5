"""The MJX backend: the whole simulation traced into the jitted program (the path for GPUs and
TPUs; on a CPU it runs, 80-120x slower than the native backend, docs/design.md)."""
from __future__ import annotations

import contextlib
import io
import sys

import jax
import jax.numpy as jnp
import numpy as np

# Without NVIDIA Warp (an optional MJX backend we do not use) importing mujoco.mjx prints two
# "Failed to import warp" lines on stdout, where our scripts print JSON: they are dropped.
with contextlib.redirect_stdout(io.StringIO()) as _printed:
  from mujoco import mjx
for _line in _printed.getvalue().splitlines():
  if not _line.startswith(('Failed to import warp:', 'Failed to import mujoco_warp:')):
    print(_line, file=sys.stderr)

from mvcoba_jax.sim.physics import CAMERA_GROUPS, Parking, SimState  # noqa: E402
from mvcoba_jax.sim.scene import Scene  # noqa: E402


def stepped(model, data, ctrl, pin, parked, frames: tuple[int, ...], steps=None,
            extra=lambda d: ()):
  """MJX's (or MuJoCo Warp's, through MJX) stepping of one tabletop through the first `steps`
  rows of `ctrl` (T, nu) (all of them if None; a traced count makes the loop's length a run-time
  value, so programs of different lengths share one compiled loop), the `parked` slots pinned
  after each step: the last Data, qpos after each step of `frames` (F, nq) and the elementwise
  maximum of `extra(data)` over the steps."""
  marks = jnp.asarray(frames, jnp.int32)

  def body(t, carry):
    d, at, most = carry
    d = pin(mjx.step(model, d.replace(ctrl=ctrl[t])), parked)
    at = jnp.where((marks == t)[:, None], d.qpos, at)
    return d, at, jax.tree.map(jnp.maximum, most, extra(d))

  start = (data, jnp.zeros((len(frames),) + data.qpos.shape, data.qpos.dtype),
           jax.tree.map(jnp.zeros_like, extra(data)))
  return jax.lax.fori_loop(0, ctrl.shape[0] if steps is None else steps, body, start)


class MjxPhysics:
  """MJX: the whole simulation is traced into the jitted program (the path for accelerators)."""

  name = 'mjx'
  traced = True  # each call site compiles MJX's step and collision functions into its program

  def __init__(self, scene: Scene, parking: Parking):
    # This process's own device: jax.devices()[0], MJX's default, may belong to another process.
    self.model = mjx.put_model(scene.mj_model, device=jax.local_devices()[0], impl='jax')
    self._parking = parking

  def _data(self, sim: SimState) -> mjx.Data:
    return mjx.make_data(self.model).replace(qpos=sim.qpos, qvel=sim.qvel,
                                             mocap_pos=sim.mocap_pos, mocap_quat=sim.mocap_quat)

  def simulate(self, sim: SimState, parked, ctrl, frames: tuple[int, ...] = (), steps=None):
    """Steps one tabletop through the first `steps` rows of `ctrl` (T, nu) (all if None);
    returns the state, whether MuJoCo was content (MJX raises no warnings: always True; the
    caller checks finiteness) and qpos after each step of `frames` (F, nq)."""
    data, at, _ = stepped(self.model, self._data(sim), ctrl, self._parking.pin, parked, frames,
                          steps)
    return sim.replace(qpos=data.qpos, qvel=data.qvel), jnp.bool_(True), at

  def cast(self, sim: SimState, origins: np.ndarray, directions: np.ndarray):
    """Distance (P,) and geom id (P,) of every ray of one tabletop; -1 for a miss."""
    data = mjx.kinematics(self.model, self._data(sim))
    return jax.vmap(lambda p, v: mjx.ray(self.model, data, p, v, geomgroup=CAMERA_GROUPS))(
        jnp.asarray(origins), jnp.asarray(directions))
