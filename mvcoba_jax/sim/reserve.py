"""A reserve of freshly dropped, settled tabletops that finished episodes swap in.

Settling a drop is a second of physics, and under vmap resetting one environment costs as much as
resetting all B. Drawing from a reserve that is refilled B states at a time, only when it runs
low, makes each reset cost one environment's settling on average.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from mvcoba_jax.sim.tabletop import EnvState, where_envs


@struct.dataclass
class Reserve:
  """Twice the batch of settled tabletops ([0, available) unused), so a refill always fits."""
  states: EnvState  # (2B,)
  available: jnp.ndarray  # int32


def _refill(reset_batch, reserve: Reserve, key, batch: int) -> Reserve:
  fresh = reset_batch(jax.random.split(key, batch))
  states = jax.tree.map(
      lambda all_, new: jax.lax.dynamic_update_slice_in_dim(all_, new, reserve.available, 0),
      reserve.states, fresh)
  return Reserve(states=states, available=reserve.available + batch)


def swap_in(reset_batch, reserve: Reserve, states: EnvState, mask, key):
  """(states, reserve): every environment in `mask` gets a fresh tabletop from the reserve.

  `reset_batch` maps B keys to B fresh states (`jax.vmap(env.reset)`, or its per-device form).

  Unhealthy environments swapped out are counted in `health_resets`, which carries over.
  """
  batch = mask.shape[0]
  reserve = jax.lax.cond(reserve.available < batch, lambda r: _refill(reset_batch, r, key, batch),
                         lambda r: r, reserve)
  rank = jnp.cumsum(mask) - 1
  source = jnp.clip(reserve.available - 1 - rank, 0, 2 * batch - 1)
  drawn = jax.tree.map(lambda x: x[source], reserve.states)
  merged = where_envs(mask, drawn, states)
  merged = merged.replace(
      health_resets=states.health_resets + (mask & ~states.healthy).astype(jnp.int32))
  return merged, reserve.replace(available=reserve.available - jnp.sum(mask, dtype=jnp.int32))
