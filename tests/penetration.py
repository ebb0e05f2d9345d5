"""Deepest interpenetration of a state, measured by native MuJoCo's collision detection."""
import mujoco
import numpy as np


def max_penetration(env, qpos) -> float:
  """Deepest contact (m, >= 0) between objects in play or with the table at these positions."""
  m = env.scene.mj_model
  d = mujoco.MjData(m)
  d.qpos[:] = np.asarray(qpos, np.float64)
  mujoco.mj_forward(m, d)
  depth = [-d.contact.dist[i] for i in range(d.ncon)]
  return max([0.0] + depth)
