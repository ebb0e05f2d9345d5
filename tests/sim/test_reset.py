"""Random drops: spread drops (the paper text's scenes) are deterministic, varied, settled and
apart; heap drops (the default preset's, the authors') settle sound on both backends; occluded
and packed shares of the drops."""
import jax
import numpy as np
import pytest

from tests.helpers import BACKENDS, make_env, make_task
from tests.penetration import max_penetration


@pytest.fixture(scope='module', params=BACKENDS)
def env(request):
  return make_env('paper_text', request.param)


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


def test_a_settled_drop_settled_again_stays_where_it_rests():
  """`Tabletop.settle` (the end of every reset, and how benchmarks compare where objects come
  to rest) moves nothing that is already at rest and keeps every object in play."""
  env = make_env('paper_text', 'native')
  state = jax.jit(env.reset)(jax.random.PRNGKey(3))
  again = jax.jit(lambda s: env.settle(s, 100))(state)
  np.testing.assert_array_equal(np.asarray(again.in_play), np.asarray(state.in_play))
  moved = np.linalg.norm(np.asarray(env.object_positions(again) - env.object_positions(state)),
                         axis=-1)[np.asarray(state.in_play)]
  assert moved.max() < 0.002, moved.max()


@pytest.mark.parametrize('backend', BACKENDS)
def test_heap_drop_settles_sound_and_closer_to_the_centre(backend):
  """env.drop='heap' (the authors' training scenes) on both physics backends, with the authors'
  preset's contact caps: objects dropped in random orientations into the central square settle
  healthy, in the workspace and without interpenetration, closer to the centre than a spread
  drop of the same objects."""
  keys = jax.random.split(jax.random.PRNGKey(3), 4)
  radius = {}
  for drop in ('heap', 'spread') if backend == 'native' else ('heap',):
    env = make_env('authors', backend, 'env.num_objects=6', f'env.drop={drop}')
    states = jax.jit(jax.vmap(env.reset))(keys)
    assert np.asarray(states.healthy).all()
    in_play = np.asarray(states.in_play)
    assert (in_play.sum(axis=1) >= 5).all(), in_play.sum(axis=1)
    pos = np.asarray(jax.vmap(env.object_positions)(states))[in_play]
    assert np.abs(pos[:, :2]).max() <= env.config.scene.workspace_half
    radius[drop] = np.median(np.hypot(pos[:, 0], pos[:, 1]))
    for b in range(states.in_play.shape[0]):
      assert max_penetration(env, states.sim.qpos[b]) < 0.003
  assert 'spread' not in radius or radius['heap'] < radius['spread'] - 0.01, radius


def test_occluded_share_hides_one_camera_wholly_or_in_part():
  """With env.occluded_share=1 every drop gets an occluder before one camera (drawn from
  `occluders.TRAINING`): that view sees none or little of the table (slot 0) or a part less
  (slot 1, 10-90% of what it would see); the other view sees as without one."""
  task = make_task('default', 'native', 'env.occluded_share=1', 'env.num_objects=3')
  states = jax.jit(jax.vmap(task.env.reset))(jax.random.split(jax.random.PRNGKey(5), 12))
  seen = np.asarray(jax.jit(task.observe)(states).seen).mean(axis=(2, 3))
  hidden, other = seen.min(axis=1), seen.max(axis=1)
  assert (other > 0.8).all() and (hidden < 0.9).all(), seen
  assert (hidden < 0.05).any() and (hidden > 0.2).any(), seen  # whole and partial both drawn
  assert (seen.argmin(axis=1) == 0).any() and (seen.argmin(axis=1) == 1).any(), seen


def test_packed_share_lays_objects_side_by_side():
  """With env.packed_share=1 every drop is one of the scene's packed arrangements: its objects
  (up to env.num_objects) settle sound in the workspace, each beside another within the family's
  widest gap (8 mm, under a finger's thickness), turned differently from drop to drop."""
  from mvcoba_jax.sim import arrangements, shapes
  keys = jax.random.split(jax.random.PRNGKey(11), 4)
  env = make_env('default', 'native', 'env.packed_share=1', 'env.occluded_share=0')
  states = jax.jit(jax.vmap(env.reset))(keys)
  assert np.asarray(states.healthy).all()
  in_play = np.asarray(states.in_play)
  assert ((in_play.sum(axis=1) >= 2) & (in_play.sum(axis=1) <= env.config.env.num_objects)).all()
  pos = np.asarray(jax.vmap(env.object_positions)(states))
  size = np.array([shapes.shape(s).rest_extent[:2].max() for s in env.scene.index.slot_shapes])
  yaws = []
  for b in range(len(keys)):
    assert max_penetration(env, states.sim.qpos[b]) < 0.002
    mine = np.flatnonzero(in_play[b])
    xy = pos[b, mine, :2]
    assert np.abs(xy).max() <= env.config.scene.workspace_half
    apart = np.linalg.norm(xy[:, None] - xy[None], axis=-1) + np.eye(len(mine))
    reach = 0.5 * (size[mine][:, None] + size[mine][None]) + arrangements.GAP[1] + 0.002
    assert (apart <= reach).any(axis=1).all(), np.round(apart.min(axis=1), 3)
    yaws.append(np.arctan2(*(xy[1] - xy[0])[::-1]))
  assert np.ptp(yaws) > 0.3, yaws


def test_the_packed_bank_holds_every_training_type_on_the_pool():
  """Arrangements of the training types only, each on distinct slots, none empty; a part whose
  shape the pool has run out of takes a shape that fits its place."""
  from mvcoba_jax.sim import arrangements
  from mvcoba_jax.sim.tabletop import packed_bank
  pool = ('cube', 'cube', 'tall_box', 'flat_box', 'cylinder')
  bank = {k: np.asarray(v) for k, v in packed_bank(pool, 4, size=8).items()}
  assert bank['in_play'].shape == (8, 5) and (bank['in_play'].sum(axis=1) >= 2).all()
  assert (bank['in_play'].sum(axis=1) <= 4).all()
  grid = bank['in_play'][1]  # a grid (the second type): cubes first, then what fits a cube
  assert arrangements.TRAINING[1] == 'grid' and grid[:2].all()
  assert not bank['in_play'][:, 3][1::4].any()  # no flat box takes a grid's square place
  for n in range(8):  # centred: every part within the bounding circle, on both sides
    xy = bank['xy'][n, bank['in_play'][n]]
    assert np.linalg.norm(xy, axis=1).max() < bank['radius'][n]
    assert (xy.min(axis=0) <= 0).all() and (xy.max(axis=0) >= 0).all()
