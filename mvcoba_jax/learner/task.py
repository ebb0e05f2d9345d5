"""The push-and-grasp task on B tabletops: the `Task` built once from a config, its state and the
one lockstep step that training and evaluation run.

An action is executed in every tabletop, the scene observed again, and the task's bookkeeping done
(docs/design.md): change observation, reward, the count of consecutive failed actions and
the end of an episode (table cleared, stuck, or bad physics). What follows an episode's end is the
caller's: training swaps in a fresh tabletop (`restart`), evaluation stops counting the run.
"""
from __future__ import annotations

import dataclasses
from typing import Callable

import jax
import jax.numpy as jnp
from flax import struct

from mvcoba_jax import perception
from mvcoba_jax.config import Config, PerceptionConfig
from mvcoba_jax.learner import agent
from mvcoba_jax.learner.replay import Transition
from mvcoba_jax.sim import contract
from mvcoba_jax.sim.tabletop import EnvState, StepInfo, Tabletop, where_envs


@struct.dataclass
class State:
  """What the task carries from one action to the next, per tabletop (B,)."""
  env: EnvState  # the scene
  obs: perception.Observation  # what the cameras see of it
  # bool: the rule meets the scene as changed (True at an episode's start; after a change, and
  # after a failed grasp that `perception.failed_grasp_retries` grasps again)
  changed: jnp.ndarray
  failures: jnp.ndarray  # int32: failed actions in a row this episode


@struct.dataclass
class Outcome:
  """What one lockstep action did, per tabletop (B,)."""
  info: StepInfo  # the physics' bookkeeping: grasp success, picked, lost, health
  changed: jnp.ndarray  # the scene changed, as reward and targets count it (False: bad physics)
  reward: jnp.ndarray
  failures: jnp.ndarray  # consecutive failed actions, this one included
  cleared: jnp.ndarray  # no object left in play
  done: jnp.ndarray  # cleared, more than `env.max_failures` failures in a row, or bad physics


def _whole(fn: Callable) -> Callable:
  return fn


@dataclasses.dataclass(frozen=True)
class Task:
  """Everything the task reads, built once from a config (`build`) and held by training and
  evaluation alike, so nothing past it reads the config: the tabletops, how the cameras' pictures
  become heightmaps, what actions earn, and the views whose heights place an action. A value:
  two tasks of equal settings are equal, so the compiled programs that take it as a static
  argument compile once for both.

  `per_env` arguments wrap per-tabletop work (`Trainer.per_env`: each device its own share)."""
  env: Tabletop
  perception: PerceptionConfig
  reward: agent.Reward
  views: tuple[int, ...]

  @classmethod
  def build(cls, config: Config, views: tuple[int, ...], frames: int = 0) -> Task:
    """The task of `config` played through `views` (the method's); `frames`: snapshots of each
    primitive `step` returns, for videos."""
    return cls(env=Tabletop(config.tabletop, frames=frames), perception=config.perception,
               reward=agent.Reward.of(config.train), views=tuple(views))

  def observe(self, states: EnvState, per_env: Callable = _whole) -> perception.Observation:
    """Heightmaps of every tabletop (B,)."""
    return per_env(jax.vmap(lambda s: perception.observe(self.env, s, self.perception)))(states)

  def to_world(self, action: agent.PixelAction, depth) -> agent.Action:
    """The primitives (B,) the pixel actions on heightmaps `depth` (B, V, R, R) stand for."""
    return agent.to_world(action, depth, self.views, self.perception.heightmap_resolution,
                          self.env.config.scene.workspace_half)

  def begin(self, states: EnvState, per_env: Callable = _whole) -> State:
    """Tabletops at the start of their episodes: observed, `changed` True, no failures."""
    b = states.in_play.shape[0]
    return State(env=states, obs=self.observe(states, per_env), changed=jnp.ones(b, bool),
                 failures=jnp.zeros(b, jnp.int32))

  def restart(self, state: State, fresh, states: EnvState, per_env: Callable = _whole) -> State:
    """`state` with the tabletops `states` in place, those where `fresh` (B,) begun anew (observed
    again, `changed` True, no failures): training's fresh tabletops for the episodes that
    ended."""
    obs = jax.lax.cond(jnp.any(fresh),
                       lambda: where_envs(fresh, self.observe(states, per_env), state.obs),
                       lambda: state.obs)
    return State(env=states, obs=obs, changed=state.changed | fresh,
                 failures=jnp.where(fresh, 0, state.failures))

  def step(self, state: State, action: agent.PixelAction,
           per_env: Callable = _whole) -> tuple[State, Outcome]:
    """Executes `action` (B,) chosen on `state.obs` in every tabletop; returns the task after it
    and the outcome."""
    world = self.to_world(action, state.obs.depth)
    states, info = per_env(jax.vmap(self.env.step))(state.env, world)
    return self._outcome(state, action, states, info, per_env)

  def step_and_settle(self, state: State, action: agent.PixelAction, drops: EnvState, settle,
                      per_env: Callable = _whole) -> tuple[State, Outcome, EnvState]:
    """`step`, and the tabletops `drops` (B,) (`Tabletop.drop`) settled when `settle` (a bool),
    in the same physics loop (`Tabletop.step_and_settle`): training's refill of fresh
    tabletops; the third result is `drops`, settled or as they were."""
    world = self.to_world(action, state.obs.depth)
    b = drops.in_play.shape[0]
    run = lambda s, a, d, f: jax.vmap(self.env.step_and_settle, in_axes=(0, 0, 0, None))(
        s, a, d, f[0])  # one flag for the batch (each device's share of it, when sharded)
    states, info, settled = per_env(run)(state.env, world, drops, jnp.broadcast_to(settle, (b,)))
    return (*self._outcome(state, action, states, info, per_env), settled)

  def _outcome(self, state: State, action: agent.PixelAction, states: EnvState, info: StepInfo,
               per_env: Callable) -> tuple[State, Outcome]:
    """The task's bookkeeping of `action`, taken in `state`, that left the tabletops `states`."""
    obs = state.obs
    next_obs = self.observe(states, per_env)
    healthy = info.healthy
    is_grasp, held = action.primitive == agent.GRASP, info.grasp_success
    changed, rule_changed = contract.observed_change(
        perception.frames_changed(obs, next_obs, self.perception) & healthy, is_grasp,
        held & healthy, state.failures, self.perception.failed_grasp_changes,
        self.perception.failed_grasp_retries, jnp)
    reward = jnp.where(healthy,
                       agent.reward(action.primitive, info.grasp_success, changed, info.lost,
                                    self.reward),
                       0.0)
    failures = contract.failures_after(state.failures, is_grasp, held, changed, jnp)
    cleared = ~jnp.any(states.in_play, axis=1)
    done = cleared | (failures > self.env.config.env.max_failures) | ~healthy
    return (State(env=states, obs=next_obs, changed=rule_changed, failures=failures),
            Outcome(info=info, changed=changed, reward=reward, failures=failures,
                    cleared=cleared, done=done))

  def transition(self, before: perception.Observation, after: State,
                 action: agent.PixelAction, out: Outcome) -> Transition:
    """The transition (B,) an action made from `before` to `after` (the task as the next action
    meets it), as training and online evaluation learn from it.

    The task goes on past an episode's end (docs/design.md; VPG does the same): the action that
    ended one bootstraps from the fresh tabletop `after` shows, which the rule meets as after a
    change. A zero future there made clearing the last object worth less than a failed grasp
    that nudged it (0.5 + gamma * Q > 1), and the learned policy avoided clearing. Only bad
    physics does not bootstrap (its next state is not a state of the task), nor, with
    `train.bootstrap_no_change` off, an action that changed nothing."""
    healthy = out.info.healthy
    no_future = ~healthy | (~out.changed if not self.reward.bootstrap_no_change else False)
    return Transition(obs=before, primitive=action.primitive, rotation=action.rotation,
                      row=action.row, col=action.col, reward=out.reward,
                      next_obs=where_envs(healthy, after.obs, before), done=no_future,
                      changed=after.changed | out.done, next_value=jnp.zeros_like(out.reward))
