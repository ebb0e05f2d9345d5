"""The push-and-grasp task on B tabletops: its state and the one lockstep step that training and
evaluation run.

An action is executed in every tabletop, the scene observed again, and the task's bookkeeping done
(docs/design.md): change observation, reward, the count of consecutive failed actions and
the end of an episode (table cleared, stuck, or bad physics). What follows an episode's end is the
caller's: training swaps in a fresh tabletop (`restart`), evaluation stops counting the run.
"""
from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp
from flax import struct

from mvcoba_jax import perception
from mvcoba_jax.config import TrainConfig
from mvcoba_jax.learner import agent
from mvcoba_jax.learner.replay import Transition
from mvcoba_jax.sim.tabletop import EnvState, StepInfo, Tabletop, where_envs


@struct.dataclass
class State:
  """What the task carries from one action to the next, per tabletop (B,)."""
  env: EnvState  # the scene
  obs: perception.Observation  # what the cameras see of it
  changed: jnp.ndarray  # bool: the last action changed the scene (True at an episode's start)
  failures: jnp.ndarray  # int32: failed actions in a row this episode


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


def begin(env: Tabletop, states: EnvState, per_env: Callable = _whole) -> State:
  """Tabletops at the start of their episodes: observed, `changed` True, no failures."""
  b = states.in_play.shape[0]
  return State(env=states, obs=observe(env, states, per_env), changed=jnp.ones(b, bool),
               failures=jnp.zeros(b, jnp.int32))


def restart(env: Tabletop, state: State, fresh, states: EnvState,
            per_env: Callable = _whole) -> State:
  """`state` with the tabletops `states` in place, those where `fresh` (B,) begun anew (observed
  again, `changed` True, no failures): training's fresh tabletops for the episodes that ended."""
  obs = jax.lax.cond(jnp.any(fresh),
                     lambda: where_envs(fresh, observe(env, states, per_env), state.obs),
                     lambda: state.obs)
  return State(env=states, obs=obs, changed=state.changed | fresh,
               failures=jnp.where(fresh, 0, state.failures))


def step(env: Tabletop, views: tuple[int, ...], state: State, action: agent.PixelAction,
         train: TrainConfig, per_env: Callable = _whole) -> tuple[State, Outcome]:
  """Executes `action` (B,) chosen on `state.obs` in every tabletop; returns the task after it
  and the outcome, rewarded as `train` says."""
  config = env.config
  obs = state.obs
  states, info = per_env(jax.vmap(env.step))(
      state.env, agent.to_world(action, obs.depth, views, config))
  next_obs = observe(env, states, per_env)
  healthy = info.healthy
  changed = perception.change_observed(obs, next_obs, info.grasp_success,
                                       config.perception) & healthy
  if not config.perception.failed_grasp_changes:
    changed &= (action.primitive != agent.GRASP) | info.grasp_success
  reward = jnp.where(healthy, agent.reward(action.primitive, info.grasp_success, changed, train),
                     0.0)
  failures = jnp.where(agent.failed(action.primitive, info.grasp_success, changed),
                       state.failures + 1, 0)
  cleared = ~jnp.any(states.in_play, axis=1)
  done = cleared | (failures > config.env.max_failures) | ~healthy
  return (State(env=states, obs=next_obs, changed=changed, failures=failures),
          Outcome(info=info, changed=changed, reward=reward, failures=failures, cleared=cleared,
                  done=done))


def transition(before: perception.Observation, after: perception.Observation,
               action: agent.PixelAction, out: Outcome, train: TrainConfig) -> Transition:
  """The transition (B,) an action made, as training and online evaluation learn from it.

  The task goes on past an episode's end (docs/design.md; VPG does the same): the action that
  ended one bootstraps from the fresh tabletop `after` shows, which the rule meets as after a
  change. A zero future there made clearing the last object worth less than a failed grasp that
  nudged it (0.5 + gamma * Q > 1), and the learned policy avoided clearing. Only bad physics
  does not bootstrap (its next state is not a state of the task), nor, with
  `train.bootstrap_no_change` off, an action that changed nothing."""
  healthy = out.info.healthy
  no_future = ~healthy | (~out.changed if not train.bootstrap_no_change else False)
  return Transition(obs=before, primitive=action.primitive, rotation=action.rotation,
                    row=action.row, col=action.col, reward=out.reward,
                    next_obs=where_envs(healthy, after, before), done=no_future,
                    changed=out.changed | out.done, next_value=jnp.zeros_like(out.reward))
