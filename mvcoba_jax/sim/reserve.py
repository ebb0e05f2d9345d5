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


def refilled(reserve: Reserve, fresh: EnvState, refill) -> Reserve:
  """`reserve` with the B settled tabletops `fresh` added when `refill` (`needs_refill`)."""
  batch = fresh.in_play.shape[0]
  states = jax.tree.map(
      lambda all_, new: jax.lax.dynamic_update_slice_in_dim(all_, new, reserve.available, 0),
      reserve.states, fresh)
  states = jax.tree.map(lambda new, old: jnp.where(refill, new, old), states, reserve.states)
  return Reserve(states=states, available=reserve.available + jnp.where(refill, batch, 0))


def needs_refill(reserve: Reserve, batch: int):
  """Whether the next `swap_in` of `batch` environments could find the reserve short."""
  return reserve.available < batch


def swap_in(reserve: Reserve, states: EnvState, mask):
  """(states, reserve): every environment in `mask` (B,) gets a fresh tabletop from the
  reserve, which must hold B (`needs_refill`, `refilled`).

  Unhealthy environments swapped out are counted in `health_resets`, which carries over.
  """
  batch = mask.shape[0]
  rank = jnp.cumsum(mask) - 1
  source = jnp.clip(reserve.available - 1 - rank, 0, 2 * batch - 1)
  drawn = jax.tree.map(lambda x: x[source], reserve.states)
  merged = where_envs(mask, drawn, states)
  merged = merged.replace(
      health_resets=states.health_resets + (mask & ~states.healthy).astype(jnp.int32))
  return merged, reserve.replace(available=reserve.available - jnp.sum(mask, dtype=jnp.int32))
