"""The task step that training and evaluation share: reward, change, failures and episode ends
from real physics (tiny scene, native backend)."""
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from mvcoba_jax.config import resolve
from mvcoba_jax.learner import agent
from mvcoba_jax.learner.agent import PixelAction
from mvcoba_jax.learner.task import State
from mvcoba_jax.sim.contract import world_to_pixel
from mvcoba_jax.sim.primitives import GRASP, PUSH
from tests.helpers import layout, make_task, stack

CUBE, CUBE2 = 0, 1


def test_rewards_failures_and_episode_ends():
  task = make_task('tiny', 'native', 'env.max_failures=2')
  env = task.env
  res, half = task.perception.heightmap_resolution, env.config.scene.workspace_half
  one_cube = layout(env, [(CUBE, 0.0, 0.0, 0.0)])
  two_cubes = layout(env, [(CUBE, 0.0, 0.0, 0.0), (CUBE2, 0.12, 0.12, 0.0)])
  states = jax.jit(jax.vmap(env.reset_from_case))(stack([one_cube, two_cubes, two_cubes,
                                                         two_cubes]))
  obs = task.observe(states)
  cube = world_to_pixel(0.0, 0.0, res, half)
  empty = world_to_pixel(-0.15, 0.15, res, half)
  behind = world_to_pixel(-0.05, 0.0, res, half)
  # The lone cube grasped (clears the table), a grasp at nothing after 2 failures (a third: more
  # than env.max_failures=2), the same after none, and a push into the cube from behind.
  rows = [(GRASP, 0, *cube), (GRASP, 0, *empty), (GRASP, 0, *empty), (PUSH, 0, *behind)]
  action = PixelAction(*(jnp.asarray(c, jnp.int32) for c in zip(*rows)))
  failures = jnp.asarray([0, 2, 0, 0], jnp.int32)
  before = State(env=states, obs=obs, changed=jnp.ones(4, bool), failures=failures)
  after, out = jax.jit(task.step)(before, action)
  next_obs = after.obs
  np.testing.assert_array_equal(np.asarray(after.failures), np.asarray(out.failures))
  np.testing.assert_array_equal(np.asarray(out.info.grasp_success), [True, False, False, False])
  np.testing.assert_array_equal(np.asarray(out.reward), [1.0, 0.0, 0.0, 0.5])
  # The same transitions under the authors' rewards (a failed grasp 0 even where it changed the
  # scene, a push that changes nothing -1), and the paper text's 0.5 for such a grasp.
  authors = agent.Reward.of(resolve('authors').train)
  np.testing.assert_array_equal(np.asarray(agent.reward(
      action.primitive, out.info.grasp_success, out.changed, out.info.lost, authors)),
      [1.0, 0.0, 0.0, 0.5])
  assert float(agent.reward(PUSH, False, False, 0, authors)) == -1.0
  assert float(agent.reward(GRASP, False, True, 0, authors)) == 0.0
  assert float(agent.reward(GRASP, False, True, 0, task.reward)) == 0.5
  # `train.lost_object_reward`, per object lost (0 here: the rewards above do not see losses).
  losing = dataclasses.replace(task.reward, lost_object=-0.25)
  assert float(agent.reward(PUSH, False, True, 2, losing)) == 0.0
  assert float(agent.reward(GRASP, True, True, 1, losing)) == 0.75
  np.testing.assert_array_equal(np.asarray(out.changed), [True, False, False, True])
  np.testing.assert_array_equal(np.asarray(out.failures), [0, 3, 1, 0])
  np.testing.assert_array_equal(np.asarray(out.cleared), [True, False, False, False])
  np.testing.assert_array_equal(np.asarray(out.done), [True, True, False, False])
  assert np.asarray(next_obs.depth[0]).max() < 0.005  # the picked cube is gone from view


def test_a_failed_grasp_that_moves_blocks_is_no_change_when_so_configured():
  """Two cubes side by side: a grasp whose fingers land on them fails and moves them, which the
  paper's rule counts as change (it grasps again); with `perception.failed_grasp_changes` off
  the same outcome is no change (the rule pushes next), though the rule grasps again after the
  first `perception.failed_grasp_retries` such grasps in a row, which reward and targets still
  count as no change. A successful grasp changes either way."""
  outcomes = {}
  settings = {'true': ('true', 0, 0), 'false': ('false', 0, 0), 'first retry': ('false', 1, 0),
              'retries spent': ('false', 1, 1)}
  for setting, (changes, retries, failures_before) in settings.items():
    task = make_task('tiny', 'native', f'perception.failed_grasp_changes={changes}',
                     f'perception.failed_grasp_retries={retries}')
    env = task.env
    res, half = task.perception.heightmap_resolution, env.config.scene.workspace_half
    two_cubes = layout(env, [(CUBE, 0.0, 0.0, 0.0), (CUBE2, 0.026, 0.0, 0.0)])
    states = jax.jit(jax.vmap(env.reset_from_case))(stack([two_cubes, two_cubes]))
    rows = [(GRASP, 0, *world_to_pixel(x, 0.0, res, half)) for x in (0.02, 0.03)]
    action = PixelAction(*(jnp.asarray(c, jnp.int32) for c in zip(*rows)))
    before = State(env=states, obs=task.observe(states), changed=jnp.ones(2, bool),
                   failures=jnp.full(2, failures_before, jnp.int32))
    after, out = jax.jit(task.step)(before, action)
    outcomes[setting] = (np.asarray(out.info.grasp_success).tolist(),
                         np.asarray(out.changed).tolist(), np.asarray(after.changed).tolist(),
                         np.asarray(out.failures).tolist())
  assert outcomes['true'] == ([False, True], [True, True], [True, True], [1, 0])
  assert outcomes['false'] == ([False, True], [False, True], [False, True], [1, 0])
  assert outcomes['first retry'] == ([False, True], [False, True], [True, True], [1, 0])
  assert outcomes['retries spent'] == ([False, True], [False, True], [False, True], [2, 0])
