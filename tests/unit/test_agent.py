"""Action choice: greedy argmax per the method's rule, and exploration on what stands on the table."""
import jax
import jax.numpy as jnp
import numpy as np

from mvcoba_jax import methods
from mvcoba_jax.learner import agent

MVCOBA = methods.get('mvcoba')

B, K, R = 256, 4, 8


def _q(seed=0):
  return jax.random.normal(jax.random.PRNGKey(seed), (B, 2, K, R, R))


def _occupied():
  """Two 'objects': a 2x2 block and a single cell; the rest is bare table."""
  cells = np.zeros((R, R), bool)
  cells[1:3, 5:7] = True
  cells[6, 2] = True
  return jnp.broadcast_to(jnp.asarray(cells), (B, R, R)), cells


def test_greedy_takes_the_argmax_of_the_rules_primitive():
  q = _q()
  changed = jnp.arange(B) % 2 == 0
  action = agent.greedy_actions(q, changed, MVCOBA)
  np.testing.assert_array_equal(action.primitive, np.where(changed, agent.GRASP, agent.PUSH))
  for i in range(4):
    chosen = np.asarray(q[i, int(action.primitive[i])])
    assert chosen[action.rotation[i], action.row[i], action.col[i]] == chosen.max()


def test_epsilon_zero_is_greedy_and_epsilon_one_explores_only_occupied_cells():
  q, changed = _q(1), jnp.ones(B, bool)
  occupied, cells = _occupied()
  greedy = agent.greedy_actions(q, changed, MVCOBA)
  action, explored = agent.epsilon_greedy(q, changed, occupied, 0.0, jax.random.PRNGKey(2), MVCOBA)
  assert not np.asarray(explored).any()
  for k in ('primitive', 'rotation', 'row', 'col'):
    np.testing.assert_array_equal(getattr(action, k), getattr(greedy, k))

  action, explored = agent.epsilon_greedy(q, changed, occupied, 1.0, jax.random.PRNGKey(3), MVCOBA)
  assert np.asarray(explored).all()
  assert (np.asarray(action.primitive) == agent.GRASP).all()  # the rule's primitive is kept
  rows, cols = np.asarray(action.row), np.asarray(action.col)
  assert cells[rows, cols].all()
  assert len(set(zip(rows.tolist(), cols.tolist()))) == cells.sum()  # every occupied cell drawn
  assert set(np.asarray(action.rotation).tolist()) == set(range(K))


def test_exploration_on_an_empty_table_draws_any_cell_and_vpg_draws_the_primitive():
  q, changed = _q(4), jnp.ones(B, bool)
  empty = jnp.zeros((B, R, R), bool)
  action, _ = agent.epsilon_greedy(q, changed, empty, 1.0, jax.random.PRNGKey(5), methods.get('vpg'))
  assert len(set(zip(np.asarray(action.row).tolist(), np.asarray(action.col).tolist()))) > R * R // 2
  assert set(np.asarray(action.primitive).tolist()) == {agent.PUSH, agent.GRASP}
