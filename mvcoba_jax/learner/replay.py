"""Prioritised experience replay that lives on the device.

The replay is a pytree of fixed-shape ring buffers with `size` and `cursor` as int32 arrays, so
`add`, `sample` and `update_priorities` are pure functions that run inside the compiled training
step, and checkpointing the pytree resumes the replay exactly.

Observations are stored compactly: colour as uint8, depth as float16 (rounding error under
0.25 mm below 0.5 m), seen as bool. Bytes per transition for 2 views at 112 x 112, s_t and
s_{t+1} each: colour 75,264 + depth 50,176 + seen 25,088 = 150,528 per observation, 301,056 for
both, plus 30 for the action, reward, flags, stored value and priority: about 294 KiB, so the default
capacity of 1024 takes about 308 MB. s_{t+1} is stored with its transition rather than shared
with the next one, which doubles the images but keeps every slot self-contained when the ring
overwrites old entries or an episode resets.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from mvcoba_jax.perception import Observation, color_to_uint8

PRIORITY_EPSILON = 1e-3  # added to |TD error| so no transition starves


@struct.dataclass
class Transition:
  """One step (s_t, a_t, r_t, s_{t+1}); fields carry a leading batch dim where batched."""
  obs: Observation
  primitive: jnp.ndarray  # int32: PUSH or GRASP
  rotation: jnp.ndarray  # int32 in [0, num_rotations)
  row: jnp.ndarray  # int32 heightmap cell of the executed pixel
  col: jnp.ndarray  # int32
  reward: jnp.ndarray  # float32
  next_obs: Observation
  done: jnp.ndarray  # bool: no bootstrap from s_{t+1} (bad physics; episodes' ends bootstrap)
  changed: jnp.ndarray  # bool: the action rule's change flag at s_{t+1} (MV-COBA's target primitive)
  next_value: jnp.ndarray  # float32: max Q(s_{t+1}) from the acting forward (train.target='acting')

  @classmethod
  def empty(cls, obs: Observation) -> Transition:
    """Transitions (B,) of nothing: `obs` as both states, every scalar zero; what waits for a
    first action's transition."""
    zeros = {name: jnp.zeros(obs.depth.shape[0], dtype) for name, dtype in _SCALARS.items()}
    return cls(obs=obs, next_obs=obs, **zeros)


_SCALARS = dict(primitive=jnp.int32, rotation=jnp.int32, row=jnp.int32, col=jnp.int32,
                reward=jnp.float32, done=jnp.bool_, changed=jnp.bool_, next_value=jnp.float32)


def _pack(obs: Observation) -> Observation:
  return Observation(color=color_to_uint8(obs.color), depth=jnp.asarray(obs.depth, jnp.float16),
                     seen=jnp.asarray(obs.seen, jnp.bool_))


def _unpack(obs: Observation) -> Observation:
  return Observation(color=obs.color.astype(jnp.float32) / 255, depth=obs.depth.astype(jnp.float32),
                     seen=obs.seen)


def _compress(t: Transition) -> Transition:
  """The storage form: packed observations, the other fields cast to their dtypes."""
  scalars = {name: jnp.asarray(getattr(t, name), dtype) for name, dtype in _SCALARS.items()}
  return t.replace(obs=_pack(t.obs), next_obs=_pack(t.next_obs), **scalars)


@struct.dataclass
class Replay:
  """`capacity` slots; slots [0, size) are filled and `cursor` is the next one written."""
  data: Transition  # leading dim capacity; observations in the packed form of `_pack`
  priority: jnp.ndarray  # (capacity,) float32; 0 in unfilled slots
  size: jnp.ndarray  # int32
  cursor: jnp.ndarray  # int32

  @property
  def capacity(self) -> int:
    return self.priority.shape[0]

  @classmethod
  def create(cls, capacity: int, obs_example: Observation) -> Replay:
    """An empty replay for observations shaped like the unbatched `obs_example`."""
    example = Transition(obs=obs_example, next_obs=obs_example,
                         **{name: jnp.zeros((), dtype) for name, dtype in _SCALARS.items()})
    data = jax.tree.map(lambda x: jnp.zeros((capacity,) + x.shape, x.dtype), _compress(example))
    return cls(data=data, priority=jnp.zeros(capacity, jnp.float32),
               size=jnp.zeros((), jnp.int32), cursor=jnp.zeros((), jnp.int32))


def add(replay: Replay, batch: Transition) -> Replay:
  """Writes the B transitions of `batch` at the cursor, overwriting the oldest when full.

  New entries get the current maximum priority (1.0 in an empty replay) so each is drawn soon
  after it arrives and gets a TD error of its own. When B exceeds the capacity only the newest
  `capacity` transitions are kept.
  """
  num = batch.reward.shape[0]
  capacity = replay.capacity
  start = replay.cursor
  if num > capacity:  # a scatter with repeated slots would keep an arbitrary one
    batch = jax.tree.map(lambda x: x[num - capacity:], batch)
    start = start + (num - capacity)
  slots = (start + jnp.arange(min(num, capacity))) % capacity
  data = jax.tree.map(lambda buf, x: buf.at[slots].set(x), replay.data, _compress(batch))
  filled = jnp.arange(capacity) < replay.size
  top = jnp.where(replay.size > 0, jnp.max(jnp.where(filled, replay.priority, 0.0)), 1.0)
  return replay.replace(data=data, priority=replay.priority.at[slots].set(top),
                        size=jnp.minimum(replay.size + num, capacity).astype(jnp.int32),
                        cursor=((replay.cursor + num) % capacity).astype(jnp.int32))


def sample(replay: Replay, key, batch_size: int, priority_exponent):
  """(indices, transitions, valid): `batch_size` draws with replacement among filled slots.

  Slot i is drawn with probability proportional to priority_i ** priority_exponent (0: uniform).
  `batch_size` is static. Callers should sample only once size >= 1; an empty replay cannot be
  refused inside a compiled step, so it returns slot 0 (zeros) with `valid` all False for the
  learner to zero the loss.
  """
  filled = jnp.arange(replay.capacity) < jnp.maximum(replay.size, 1)
  # The floor keeps the logits finite at the empty replay's slot 0 (priority 0), also for alpha 0.
  weight = jnp.log(jnp.maximum(replay.priority, PRIORITY_EPSILON))
  logits = jnp.where(filled, priority_exponent * weight, -jnp.inf)
  indices = jax.random.categorical(key, logits, shape=(batch_size,))
  picked = jax.tree.map(lambda buf: buf[indices], replay.data)
  picked = picked.replace(obs=_unpack(picked.obs), next_obs=_unpack(picked.next_obs))
  return indices, picked, jnp.broadcast_to(replay.size > 0, (batch_size,))


def update_priorities(replay: Replay, indices, td_errors) -> Replay:
  """Priority |TD error| + epsilon at `indices` (a slot drawn twice gets one of its values)."""
  priority = jnp.abs(jnp.asarray(td_errors, jnp.float32)) + PRIORITY_EPSILON
  return replay.replace(priority=replay.priority.at[indices].set(priority))
