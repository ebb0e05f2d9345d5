"""The push-and-grasp task on B tabletops: the one lockstep step that training and evaluation run.

An action is executed in every tabletop, the scene observed again, and the task's bookkeeping done
(docs/design.md): change observation, reward, the count of consecutive failed actions and
the end of an episode (table cleared, stuck, or bad physics). What follows an episode's end is the
caller's: training swaps in a fresh tabletop, evaluation stops counting the run.
"""
from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp
from flax import struct

from mvcoba_jax import agent, perception
from mvcoba_jax.config import TrainConfig
from mvcoba_jax.sim.tabletop import EnvState, StepInfo, Tabletop


@struct.dataclass
class Outcome:
  """What one lockstep action did, per tabletop (B,)."""
  info: StepInfo  # the physics' bookkeeping: grasp success, picked, lost, health
  changed: jnp.ndarray  # the scene changed (always False for bad physics)
  reward: jnp.ndarray
  failures: jnp.ndarray  # consecutive failed actions, this one included
  cleared: jnp.ndarray  # no object left in play
  done: jnp.ndarray  # cleared, more than `env.max_failures` failures in a row, or bad physics


def _whole(fn: Callable) -> Callable:
  return fn


def observe(env: Tabletop, states: EnvState, per_env: Callable = _whole) -> perception.Observation:
  """Heightmaps of every tabletop (B,). `per_env` wraps per-tabletop work (`Trainer.per_env`)."""
  return per_env(jax.vmap(lambda s: perception.observe(env, s)))(states)


def step(env: Tabletop, views: tuple[int, ...], states: EnvState, obs: perception.Observation,
         failures, action: agent.PixelAction, train: TrainConfig,
         per_env: Callable = _whole) -> tuple[EnvState, perception.Observation, Outcome]:
  """Executes `action` (B,) chosen on `obs` in every tabletop; returns the tabletops, what they
  look like now and the outcome, rewarded as `train` says."""
  config = env.config
  states, info = per_env(jax.vmap(env.step))(
      states, agent.to_world(action, obs.depth, views, config))
  next_obs = observe(env, states, per_env)
  healthy = info.healthy
  changed = perception.change_observed(obs, next_obs, info.grasp_success,
                                       config.perception) & healthy
  reward = jnp.where(healthy, agent.reward(action.primitive, info.grasp_success, changed, train),
                     0.0)
  failures = jnp.where(agent.failed(action.primitive, info.grasp_success, changed),
                       failures + 1, 0)
  cleared = ~jnp.any(states.in_play, axis=1)
  done = cleared | (failures > config.env.max_failures) | ~healthy
  return states, next_obs, Outcome(info=info, changed=changed, reward=reward, failures=failures,
                                   cleared=cleared, done=done)
