"""Random drops on the default scene: determinism, variety, no interpenetration."""
import jax
import numpy as np
import pytest

from tests.helpers import BACKENDS, make_env
from tests.penetration import max_penetration


@pytest.fixture(scope='module', params=BACKENDS)
def env(request):
  return make_env('default', request.param)


@pytest.fixture(scope='module')
def states(env):
  keys = jax.random.split(jax.random.PRNGKey(7), 3)
  keys = np.stack([keys[0], keys[0], keys[1], keys[2]])
  return jax.jit(jax.vmap(env.reset))(keys)


def test_same_key_same_state_different_keys_different_layouts(env, states):
  qpos = np.asarray(states.sim.qpos)
  np.testing.assert_array_equal(qpos[0], qpos[1])
  pos = np.asarray(jax.vmap(env.object_positions)(states))
  for other in (2, 3):
    assert np.abs(pos[0] - pos[other]).max() > 0.02
  assert not np.array_equal(np.asarray(states.in_play[2]), np.asarray(states.in_play[3])) or \
      np.abs(pos[2] - pos[3]).max() > 0.02


def test_drop_settles_all_objects_inside_the_workspace(env, states):
  n = env.config.env.num_objects
  in_play = np.asarray(states.in_play)
  assert (in_play.sum(axis=1) >= n - 1).all(), in_play.sum(axis=1)
  pos = np.asarray(jax.vmap(env.object_positions)(states))
  h = env.config.scene.workspace_half
  assert (np.abs(pos[in_play][:, :2]) <= h).all()
  assert (pos[in_play][:, 2] > 0.0).all() and (pos[in_play][:, 2] < 0.2).all()
  assert np.asarray(states.healthy).all()
  # Settled: nothing moves faster than 5 cm/s.
  qvel = np.asarray(states.sim.qvel)
  assert np.abs(qvel[:, 6:]).max() < 0.05


def test_no_interpenetration_after_settling(env, states):
  for b in range(states.in_play.shape[0]):
    assert max_penetration(env, states.sim.qpos[b]) < 0.002
