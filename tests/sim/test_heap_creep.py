"""A settled heap left alone stays where it settled under MuJoCo's noslip pass
(`scene.noslip_iterations`); without it, soft contacts let objects resting on others creep off.
`benchmarks/heap_creep.py` measures the same over whole suites."""
import mujoco
import numpy as np
import pytest

from mvcoba_jax.config import resolve
from mvcoba_jax.sim.scenarios import read_case
from mvcoba_jax.suites import SUITES_DIR
from mvcoba_jax.suites.cases import settled_starts

HEAP = SUITES_DIR / 'dev-random' / 'dev-random-03.scn'  # 33 objects, piled up to 14 cm
IDLE_S = 20.0


def slides_when_left_alone(noslip: int) -> np.ndarray:
  """How far (m) each object in play slides in IDLE_S with the gripper parked, native MuJoCo."""
  config = resolve('default', ['scene.backend=native', f'scene.noslip_iterations={noslip}'])
  env, starts = settled_starts([read_case(HEAP)], config, runs=1)
  model = env.scene.mj_model
  assert model.opt.noslip_iterations == noslip
  data = mujoco.MjData(model)
  data.qpos[:] = np.asarray(starts.sim.qpos[0])
  data.mocap_pos[:], data.mocap_quat[:] = starts.sim.mocap_pos[0], starts.sim.mocap_quat[0]
  data.ctrl[:] = data.qpos[env.scene.index.gripper_qpos]
  xy = np.asarray(env.scene.index.slot_qpos)[:, None] + np.arange(2)
  before = data.qpos[xy].copy()
  for _ in range(round(IDLE_S / model.opt.timestep)):
    mujoco.mj_step(model, data)
  play = np.asarray(starts.in_play[0])
  assert play.sum() == 33
  return np.linalg.norm(data.qpos[xy] - before, axis=1)[play]


@pytest.mark.parametrize('noslip', [0, 10])
def test_settled_heap_left_alone_stays_only_with_the_noslip_pass(noslip):
  slid = slides_when_left_alone(noslip)
  if noslip:
    assert slid.max() < 0.01, f'slid (cm): {np.round(100 * np.sort(slid)[-5:], 1)}'
  else:
    assert (slid > 0.01).sum() >= 5, f'slid (cm): {np.round(100 * np.sort(slid)[-5:], 1)}'
