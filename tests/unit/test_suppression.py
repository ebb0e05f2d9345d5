"""CPG's suppression: which actions it lets act, and that its rule never picks a suppressed one."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mvcoba_jax import methods
from mvcoba_jax.config import resolve
from mvcoba_jax.learner import agent, networks, suppression
from mvcoba_jax.sim.primitives import GRASP, PUSH

RES, SIDE, K = 0.004, 112, 16
factors = jax.jit(lambda h: suppression.factors(h, K, RES))


def blocks(*cells):
  """(1, R, R) heights: a 5 cm cube (12 x 12 cells) with its top-left cell at each (row, col)."""
  h = np.zeros((1, SIDE, SIDE), np.float32)
  for r, c in cells:
    h[0, r:r + 12, c:c + 12] = 0.05
  return jnp.asarray(h)


def test_fingers_landing_on_a_neighbour_suppress_the_grasp():
  """Two cubes side by side along x (cols), one cell apart: a grasp at the first's centre is
  free with the fingers along y (rotation 0) and suppressed along x (rotation 4, on the other
  cube); no grasp on bare table."""
  f = np.asarray(factors(blocks((50, 50), (50, 63))))
  assert f[0, GRASP, 0, 56, 56] == 1.0
  assert f[0, GRASP, 4, 56, 56] == 0.0
  assert f[0, GRASP, 0, 20, 20] == 0.0


def test_pushes_need_something_ahead_and_start_off_an_edge():
  f = np.asarray(factors(blocks((50, 50))))
  assert f[0, PUSH, 0, 56, 46] > 0.5  # 1-2.5 cm left of the cube, pushing +x into it
  assert f[0, PUSH, 8, 56, 46] == 0.0  # the same start pushing away
  assert f[0, PUSH, 0, 56, 30] == 0.0  # 8 cm off: outside CPG's ring
  assert f[0, PUSH, 0, 56, 56] == 0.0  # on top of the cube


@pytest.mark.parametrize('seed', range(4))
def test_the_rule_never_picks_a_suppressed_action(seed):
  """Random Q maps over a random clutter of cubes: CPG's greedy action always has a factor above
  0, and the raw maxima it passes over are suppressed ones."""
  rng = np.random.default_rng(seed)
  heights = np.concatenate([blocks(*rng.integers(5, 95, (6, 2))) for _ in range(3)])
  q = jax.random.normal(jax.random.PRNGKey(seed), (3, 2, K, SIDE, SIDE))
  depth = jnp.asarray(heights)[:, None]  # one view
  config = resolve('default')
  maps = agent.Decision.of(methods.get('cpg'), config).maps(q, depth)
  action = agent.greedy_actions(maps, jnp.ones(3, bool), methods.get('cpg'))
  f = np.asarray(factors(jnp.asarray(heights)))
  picked = f[np.arange(3), np.asarray(action.primitive), np.asarray(action.rotation),
             np.asarray(action.row), np.asarray(action.col)]
  assert (picked > 0).all(), picked
  raw = agent.greedy_actions(q, jnp.ones(3, bool), methods.get('vpg'))
  raw_f = f[np.arange(3), np.asarray(raw.primitive), np.asarray(raw.rotation),
            np.asarray(raw.row), np.asarray(raw.col)]
  changed = np.asarray(raw.row) != np.asarray(action.row)
  assert (raw_f[changed] == 0).all() and changed.any()


def test_with_nothing_allowed_the_raw_maps_decide():
  q = jax.random.normal(jax.random.PRNGKey(0), (1, 2, K, SIDE, SIDE))
  empty = jnp.zeros((1, 1, SIDE, SIDE))
  maps = agent.Decision.of(methods.get('cpg'), resolve('default')).maps(q, empty)
  np.testing.assert_array_equal(np.asarray(maps), np.asarray(q))
  assert not np.any(np.asarray(maps) == networks.NO_ACTION)


def test_mvcoba_with_suppression_grasps_and_pushes_only_where_allowed():
  """`network.suppress` in MV-COBA's change rule: after a change it grasps where the fingers
  land free, after none it pushes with something ahead, over random Q maps and cube clutter
  seen by both views; without the setting its maps are the raw Q maps."""
  rng = np.random.default_rng(7)
  heights = jnp.asarray(np.concatenate([blocks(*rng.integers(5, 95, (6, 2))) for _ in range(2)]))
  q = jax.random.normal(jax.random.PRNGKey(7), (2, 2, K, SIDE, SIDE))
  depth = jnp.stack([heights, heights], axis=1)  # two views
  method, config = methods.get('mvcoba'), resolve('default', ['network.suppress=true'])
  maps = agent.Decision.of(method, config).maps(q, depth)
  f = np.asarray(factors(heights))
  for changed, primitive in ((True, GRASP), (False, PUSH)):
    action = agent.greedy_actions(maps, jnp.full(2, changed), method)
    assert (np.asarray(action.primitive) == primitive).all()
    picked = f[np.arange(2), primitive, np.asarray(action.rotation), np.asarray(action.row),
               np.asarray(action.col)]
    assert (picked > 0).all(), picked
  assert agent.Decision.of(method, resolve('reproduction')).maps(q, depth) is q


def test_a_given_primitive_with_nothing_allowed_keeps_its_raw_map():
  """Blocks over the whole map: no push starts off an edge, a few grasps at the map's border are
  free. A rule given its primitive (change, after no change: push) then reads the push's raw Q
  map, never an all-suppressed one whose argmax is a corner; CPG's rule, which compares
  primitives, keeps the pushes suppressed and so grasps."""
  height = jnp.full((1, SIDE, SIDE), 0.05)
  f = np.asarray(factors(height))
  assert not (f[0, PUSH] > 0).any() and (f[0, GRASP] > 0).any()
  q = jax.random.normal(jax.random.PRNGKey(1), (1, 2, K, SIDE, SIDE))
  given = np.asarray(suppression.scores(q, height, RES, per_primitive=True))
  np.testing.assert_array_equal(given[:, PUSH], np.asarray(q[:, PUSH]))
  assert (given[:, GRASP] == networks.NO_ACTION).any()
  compared = np.asarray(suppression.scores(q, height, RES))
  assert (compared[:, PUSH] == networks.NO_ACTION).all()
  action = agent.greedy_actions(jnp.asarray(compared), jnp.zeros(1, bool), methods.get('cpg'))
  assert int(action.primitive[0]) == GRASP


def test_push_room_keeps_pushes_from_heading_over_the_border():
  """A cube 2 cm from the +x border: pushing it +x (towards the border, 3 cm of room) is allowed
  without `push_room` and suppressed with 15 cm; pushing it -x from its border side (room 38 cm)
  stays allowed; the room of a cell is its distance to the border along the push."""
  height = blocks((50, 95))  # cols 95-106 of 112: the cube's +x face 5 cells from the border
  room = np.asarray(suppression.room_ahead(SIDE, K, RES))
  assert abs(room[0, 56, 90] - (SIDE - 90 - 0.5) * RES) < 1e-6  # +x from col 90
  assert abs(room[8, 56, 90] - (90 + 0.5) * RES) < 1e-6  # -x
  assert abs(room[4, 10, 56] - (SIDE - 10 - 0.5) * RES) < 1e-6  # +y (rows)
  free = np.asarray(suppression.factors(height, K, RES))
  kept = np.asarray(suppression.factors(height, K, RES, push_room=0.15))
  assert free[0, PUSH, 0, 56, 91] > 0 and kept[0, PUSH, 0, 56, 91] == 0  # +x, 8.4 cm of room
  assert free[0, PUSH, 8, 56, 110] > 0 and kept[0, PUSH, 8, 56, 110] > 0  # -x, 44.2 cm
  np.testing.assert_array_equal(free[:, GRASP], kept[:, GRASP])
  np.testing.assert_array_equal(np.asarray(suppression.factors(height, K, RES, push_room=0.0)),
                                free)
