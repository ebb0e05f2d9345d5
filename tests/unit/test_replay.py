"""Device replay: ring writes, compression, prioritised sampling, checkpoint round trip."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mvcoba_jax.learner import replay as rp
from mvcoba_jax.perception import Observation

VIEWS, SIDE = 2, 4
add = jax.jit(rp.add)
sample = jax.jit(rp.sample, static_argnums=2)
update_priorities = jax.jit(rp.update_priorities)


def observations(num, seed=0):
  rng = np.random.default_rng(seed)
  return Observation(color=rng.uniform(0, 1, (num, VIEWS, SIDE, SIDE, 3)).astype(np.float32),
                     depth=rng.uniform(0, 0.3, (num, VIEWS, SIDE, SIDE)).astype(np.float32),
                     seen=rng.uniform(size=(num, VIEWS, SIDE, SIDE)) < 0.7)


def transitions(ids):
  """A batch whose reward (and row) carries an id to tell entries apart."""
  ids = np.asarray(ids)
  num = len(ids)
  return rp.Transition(obs=observations(num, seed=int(ids[0])),
                       next_obs=observations(num, seed=int(ids[0]) + 1000),
                       primitive=ids % 2, rotation=ids % 16, row=ids, col=ids + 1,
                       reward=ids.astype(np.float32), done=ids % 3 == 0, changed=ids % 2 == 1,
                       next_value=-ids.astype(np.float32))


def filled(capacity, num):
  replay = rp.Replay.create(capacity, jax.tree.map(lambda x: x[0], observations(1)))
  return add(replay, transitions(np.arange(num)))


def counts(replay, key, draws, alpha):
  indices, _, _ = sample(replay, key, draws, alpha)
  return np.bincount(np.asarray(indices), minlength=replay.capacity)


def test_add_wraps_and_keeps_newest():
  replay = filled(4, 3)
  replay = add(replay, transitions(np.arange(3, 6)))
  assert int(replay.size) == 4 and int(replay.cursor) == 2
  np.testing.assert_array_equal(replay.data.reward, [4, 5, 2, 3])
  np.testing.assert_array_equal(replay.data.col, [5, 6, 3, 4])
  big = add(replay, transitions(np.arange(6, 12)))  # more than the capacity at once
  assert int(big.size) == 4 and int(big.cursor) == 0
  np.testing.assert_array_equal(big.data.reward, [8, 9, 10, 11])


def test_compression_round_trip():
  replay = filled(8, 5)
  batch = transitions(np.arange(5))
  indices, got, valid = sample(replay, jax.random.key(0), 32, 0.0)
  assert valid.all()
  assert replay.data.obs.color.dtype == jnp.uint8 and replay.data.obs.depth.dtype == jnp.float16
  for name in ('obs', 'next_obs'):
    want = jax.tree.map(lambda x: x[np.asarray(indices)], getattr(batch, name))
    have = getattr(got, name)
    assert have.color.dtype == jnp.float32 and have.depth.dtype == jnp.float32
    np.testing.assert_allclose(have.color, want.color, atol=0.5 / 255 + 1e-6)
    np.testing.assert_allclose(have.depth, want.depth, rtol=1e-3, atol=1e-6)
    np.testing.assert_array_equal(have.seen, want.seen)
  for name in ('primitive', 'rotation', 'row', 'col', 'reward', 'done', 'changed'):
    np.testing.assert_array_equal(getattr(got, name), getattr(batch, name)[np.asarray(indices)])


def test_sampling_only_filled_slots():
  replay = filled(16, 3)
  indices, _, valid = sample(replay, jax.random.key(1), 200, 0.6)
  assert valid.all() and np.asarray(indices).max() < 3
  empty = rp.Replay.create(16, jax.tree.map(lambda x: x[0], observations(1)))
  for alpha in (0.0, 0.6):
    indices, got, valid = sample(empty, jax.random.key(1), 8, alpha)
    assert not np.asarray(valid).any()
    np.testing.assert_array_equal(indices, 0)
    assert np.isfinite(got.obs.depth).all()


def test_priorities_steer_sampling():
  replay = filled(16, 10)
  np.testing.assert_array_equal(replay.priority[:10], 1.0)
  uniform = counts(replay, jax.random.key(2), 2000, 0.0)
  assert uniform[10:].sum() == 0 and uniform[:10].min() > 120 and uniform[:10].max() < 280
  # Slot 3 gets 100x the priority of the others.
  replay = update_priorities(replay, jnp.arange(10), jnp.where(jnp.arange(10) == 3, 0.999, -0.009))
  skewed = counts(replay, jax.random.key(2), 2000, 1.0)
  assert skewed[3] > 1600  # expected 100/109 of the draws
  flat = counts(replay, jax.random.key(2), 2000, 0.0)  # alpha 0 ignores priorities
  assert flat[3] < 300
  # New entries get the current maximum priority.
  replay = add(replay, transitions(np.arange(10, 12)))
  np.testing.assert_allclose(replay.priority[10:12], 1.0)


def test_checkpoint_round_trip_samples_identically():
  replay = filled(8, 6)
  replay = update_priorities(replay, jnp.arange(6), jnp.arange(6.0))
  restored = jax.tree.map(np.asarray, replay)
  assert isinstance(restored, rp.Replay) and isinstance(restored.size, np.ndarray)
  for a, b in zip(jax.tree.leaves(sample(replay, jax.random.key(3), 16, 0.6)),
                  jax.tree.leaves(sample(restored, jax.random.key(3), 16, 0.6))):
    np.testing.assert_array_equal(a, b)
  more = transitions(np.arange(20, 23))
  for a, b in zip(jax.tree.leaves(add(replay, more)), jax.tree.leaves(add(restored, more))):
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize('batch', [1, 3])
def test_cursor_and_size_stay_int32(batch):
  replay = add(filled(4, 3), transitions(np.arange(10, 10 + batch)))
  assert replay.size.dtype == jnp.int32 and replay.cursor.dtype == jnp.int32
  assert int(replay.size) == 4 and int(replay.cursor) == (3 + batch) % 4
