"""One jit-compiled training step for B tabletops in lockstep, and K of them per call.

act -> primitive physics -> render -> heightmaps -> change observation -> reward -> replay write
-> sample -> SGD update -> auto-reset of finished environments. The whole training state is one
pytree (`TrainState`), so a checkpoint is that pytree and resuming is exact.
"""
from __future__ import annotations

import functools
import hashlib
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx, struct
from jax.sharding import Mesh, PartitionSpec

from mvcoba_jax import perception
from mvcoba_jax.config import Config
from mvcoba_jax.learner import agent, networks, task
from mvcoba_jax.learner import replay as replay_lib
from mvcoba_jax.sim import reserve as reserve_lib


@struct.dataclass
class TrainState:
  task: task.State  # (B,) tabletops, what they look like, last change, failures in a row
  reserve: reserve_lib.Reserve  # settled tabletops for episodes that end
  params: Any
  target_params: Any
  opt_state: Any
  replay: replay_lib.Replay
  # train.target='acting': the last step's transitions (B,), stored once this step's acting
  # forward has valued their next state; `pending_valid` once there are any.
  pending: replay_lib.Transition
  pending_valid: jnp.ndarray
  key: jnp.ndarray
  actions: jnp.ndarray  # int32: actions executed so far, over all environments
  updates: jnp.ndarray  # int32: SGD updates applied
  skipped_updates: jnp.ndarray  # int32: updates refused for a non-finite loss or parameter
  episodes: jnp.ndarray  # int32: episodes finished (cleared, stuck or bad physics)


@struct.dataclass
class StepLog:
  """What happened in one lockstep action, per environment (B,) unless noted."""
  primitive: jnp.ndarray
  grasp_success: jnp.ndarray
  changed: jnp.ndarray
  reward: jnp.ndarray
  done: jnp.ndarray
  healthy: jnp.ndarray
  picked: jnp.ndarray
  lost: jnp.ndarray
  loss: jnp.ndarray  # scalar: the update's loss (0 when no update ran)
  epsilon: jnp.ndarray  # scalar
  explored: jnp.ndarray  # a random action, not the policy's


class Trainer:
  """Static parts of training (environment, network graph, optimiser); methods are pure.

  With a `mesh` of several devices the state must be placed with `sharding.place`: physics,
  rendering and resets then run per device on its share of the environments (`shard_map`), and
  XLA partitions the rest (acting, replay, the update with its gradient reduction).
  """

  def __init__(self, config: Config, mesh: Mesh | None = None):
    self.config = config
    self.mesh = mesh if mesh is not None and mesh.devices.size > 1 else None
    model = networks.build_network(config.network, config.env.num_rotations, nnx.Rngs(0))
    self.method = model.method  # the network carries its method
    self.decision = agent.Decision.of(self.method, config)
    self.task = task.Task.build(config, self.method.views)
    self.graphdef, _ = nnx.split(model)
    self.optimizer = agent.optimizer(config.train)

  # ---------------------------------------------------------------- network
  def q_maps(self, params, obs: perception.Observation, rotations=None):
    return nnx.merge(self.graphdef, params)(obs.color, obs.depth, rotations)

  def init_params(self, key):
    model = networks.build_network(self.config.network, self.config.env.num_rotations,
                                   nnx.Rngs(params=key))
    return nnx.split(model)[1]

  def per_env(self, fn):
    """`fn` over a batch of environments, run by each device on its own share when sharded.

    Environments are independent, so nothing crosses devices and XLA's partitioner has nothing
    to decide inside the physics' loops.
    """
    if self.mesh is None:
      return fn
    return jax.shard_map(fn, mesh=self.mesh, in_specs=PartitionSpec('data'),
                         out_specs=PartitionSpec('data'), check_vma=False)

  def observe(self, env_states):
    return self.task.observe(env_states, self.per_env)

  # ---------------------------------------------------------------- state
  def init(self, key) -> TrainState:
    """Fresh parameters, an empty replay, B freshly dropped tabletops and a full reserve."""
    b = self.config.num_envs
    k_params, k_env, key = jax.random.split(key, 3)
    params = self.init_params(k_params)
    dropped = jax.vmap(self.task.env.reset)(jax.random.split(k_env, 3 * b))  # one compiled reset
    begun = self.task.begin(jax.tree.map(lambda x: x[:b], dropped), self.per_env)
    obs = begun.obs
    example = jax.tree.map(lambda x: x[0], obs)
    return TrainState(
        task=begun,
        reserve=reserve_lib.Reserve(states=jax.tree.map(lambda x: x[b:], dropped),
                                    available=jnp.int32(2 * b)),
        params=params, target_params=params, opt_state=self.optimizer.init(params),
        replay=replay_lib.Replay.create(self.config.train.replay_capacity, example),
        pending=replay_lib.Transition.empty(obs), pending_valid=jnp.bool_(False), key=key,
        actions=jnp.int32(0), updates=jnp.int32(0), skipped_updates=jnp.int32(0),
        episodes=jnp.int32(0))

  # ---------------------------------------------------------------- learning
  def loss(self, params, target_params, batch, valid):
    """`agent.executed_loss` of the sampled transitions against their bootstrap targets: the
    stored next-state value (`train.target='acting'`) or the target network's."""
    t = self.config.train
    if t.target == 'acting':
      y = agent.bootstrap(batch.next_value, batch.done, batch.reward, t)
    else:
      q_next = self.q_maps(target_params, batch.next_obs)
      y = agent.target_value(q_next, batch.changed, batch.done, batch.reward, self.method, t)
    return agent.executed_loss(self.q_maps, params, batch, y, valid, self.config.train,
                               self.config.env.num_rotations)

  def update(self, state: TrainState, key, enabled=True,
             fresh: tuple[replay_lib.Transition, jnp.ndarray] | None = None
             ) -> tuple[TrainState, jnp.ndarray]:
    """One SGD step on a prioritised batch (each replayed transition turned by random quarter
    turns with `train.quarter_turns`); a non-finite loss or parameter leaves all as it was.

    `fresh`: (transitions, whether they are valid) trained on too, in the same step, after the
    sampled ones (`train.fresh_in_batch`); their priorities are not updated here, since each
    was just written with the replay's highest. Without `enabled` the step is computed and
    discarded: selecting its result costs far less on a CPU than branching around it, since
    XLA's CPU backend runs the update inside `lax.cond` 5 times slower
    (docs/results/native-backend.md). Returns the state and the loss per transition (0 when the
    step was refused or not enabled).
    """
    t = self.config.train
    key, k_turns = jax.random.split(key) if t.quarter_turns else (key, None)
    index, batch, valid = replay_lib.sample(state.replay, key, t.batch_size, t.priority_exponent)
    if t.quarter_turns:
      turns = jax.random.randint(k_turns, (t.batch_size,), 0, 4)
      batch = agent.quarter_turned(batch, turns, self.config.env.num_rotations)
    if fresh is not None:
      transitions, fresh_valid = fresh
      batch = jax.tree.map(lambda a, b: jnp.concatenate([a, b.astype(a.dtype)]), batch,
                           transitions)
      valid = jnp.concatenate([valid, jnp.broadcast_to(fresh_valid, transitions.reward.shape)])
    params, opt_state, loss, td, sound = agent.sgd_step(
        self.loss, self.optimizer, state.params, state.opt_state, state.target_params, batch,
        valid)
    td = td[:t.batch_size]
    ok = enabled & sound
    keep = lambda new, old: jax.tree.map(lambda a, b: jnp.where(ok, a, b), new, old)
    params, opt_state = keep(params, state.params), keep(opt_state, state.opt_state)
    count = state.updates + ok.astype(jnp.int32)
    copy = ok & (count % t.target_update_period == 0)
    target = jax.tree.map(lambda a, b: jnp.where(copy, a, b), params, state.target_params)
    priority = replay_lib.update_priorities(state.replay, index, td).priority
    replay = state.replay.replace(priority=jnp.where(ok, priority, state.replay.priority))
    skipped = state.skipped_updates + (enabled & ~sound).astype(jnp.int32)
    state = state.replace(params=params, target_params=target, opt_state=opt_state,
                          replay=replay, updates=count, skipped_updates=skipped)
    mean_loss = loss / jnp.maximum(jnp.sum(valid), 1)  # logged per transition, for any batch
    return state, jnp.where(ok, mean_loss, 0.0)

  # ---------------------------------------------------------------- one lockstep action
  def step(self, state: TrainState, learn, epsilon) -> tuple[TrainState, StepLog]:
    """Every environment acts once; with `learn`, the transition is stored and
    `config.updates_per_step` updates run (`train.replay_ratio`).

    `epsilon` >= 0 overrides the schedule (0 for greedy evaluation); traced, like `learn`, so one
    compiled program serves training and evaluation.
    """
    t = self.config.train
    key, k_act, k_learn, k_reset = jax.random.split(state.key, 4)
    eps = jnp.where(epsilon >= 0, epsilon, agent.epsilon_at(state.actions, t))
    before = state.task
    q = self.q_maps(state.params, before.obs)
    occupied = agent.surface_height(before.obs.depth, self.method.views) > t.explore_min_height
    action, explored = self.decision.explore(q, before.obs.depth, before.changed, occupied, eps,
                                             k_act)
    # Fresh tabletops for the reserve settle in the primitive's physics loop, when it runs low.
    b = action.primitive.shape[0]
    refill = reserve_lib.needs_refill(state.reserve, b)
    drops = self.per_env(jax.vmap(self.task.env.drop))(jax.random.split(k_reset, b))
    after, out, drops = self.task.step_and_settle(before, action, drops, refill, self.per_env)
    info, healthy, changed, done = out.info, out.info.healthy, out.changed, out.done
    reserve = reserve_lib.refilled(state.reserve, drops, refill)
    env_states, reserve = reserve_lib.swap_in(reserve, after.env, done)
    after = self.task.restart(after, done, env_states, self.per_env)

    transition = self.task.transition(before.obs, after, action, out)
    if t.target == 'acting':
      # The last step's transitions led to the states acted on now (or ended in bad physics,
      # which does not bootstrap): this step's forward values their next states.
      store = state.pending.replace(
          next_value=agent.future_value(q, before.changed, self.method, t))
      add = learn & state.pending_valid
      state = state.replace(
          pending=jax.tree.map(lambda new, old: jnp.where(learn, new, old), transition,
                               state.pending),
          pending_valid=state.pending_valid | learn)
    else:
      store, add = transition, learn
    state, loss = self.learn(state, store, add, learn, k_learn)
    state = state.replace(
        task=after, reserve=reserve, key=key, actions=state.actions + b,
        episodes=state.episodes + jnp.sum(done, dtype=jnp.int32))
    log = StepLog(primitive=action.primitive, grasp_success=info.grasp_success, changed=changed,
                  reward=out.reward, done=done, healthy=healthy, picked=info.picked, lost=info.lost,
                  loss=loss, epsilon=eps, explored=explored)
    return state, log

  def learn(self, state: TrainState, store: replay_lib.Transition, add, learn, key
            ) -> tuple[TrainState, jnp.ndarray]:
    """Stores `store` when `add`, then runs `config.updates_per_step` updates when `learn` and
    the replay holds any transition; the state and the updates' mean loss."""
    t = self.config.train
    replay = jax.lax.cond(add, lambda r: replay_lib.add(r, store), lambda r: r, state.replay)
    state = state.replace(replay=replay)
    fresh = (store, add) if t.fresh_in_batch else None
    keys, enabled = jax.random.split(key, self.config.updates_per_step), learn & (replay.size > 0)
    if len(keys) == 1 or jax.default_backend() == 'cpu':  # written out on a CPU, as `iterate`
      losses = []
      for k in keys:
        state, loss = self.update(state, k, enabled, fresh)
        losses.append(loss)
      return state, sum(losses) / len(losses)
    state, losses = jax.lax.scan(lambda s, k: self.update(s, k, enabled, fresh), state, keys)
    return state, jnp.mean(losses)

  def iterate(self, state: TrainState, learn, epsilon) -> tuple[TrainState, StepLog]:
    """`train.steps_per_iteration` lockstep actions in one program (StepLog gains a K axis);
    `compiled` is how training calls it.

    On a CPU the K steps are written out one after the other, not looped: XLA's CPU backend runs
    the SGD update inside a loop body (a `lax.scan`, even of length 1) or a `lax.cond` branch 3-5
    times slower than outside one (at B=8, 7.6 s per step looped, 1.9 s written out), at the
    price of compiling K steps. Accelerators keep the loop and its short compile.
    """
    k = self.config.train.steps_per_iteration
    if jax.default_backend() != 'cpu':
      return jax.lax.scan(lambda s, _: self.step(s, learn, epsilon), state, None, length=k)
    return _one_after_another(self.step, k, state, learn, epsilon)

  @property
  def per_step(self) -> bool:
    """Whether `compiled` calls the one-step program K times rather than one program of K steps:
    on a CPU with physics traced into the program (MJX), where the K written-out steps would hold
    K copies of MJX's step and collision functions (at 8 tabletops and K=4, 249 s to compile
    against 88-95 s, for about 10 % more time per step: docs/results/mjx-compile.md). Native
    physics is a host call, cheap to compile, and K calls of its one step ran 6-28 % slower."""
    return jax.default_backend() == 'cpu' and self.task.env.backend.traced

  def compiled(self, per_step: bool | None = None):
    """`iterate` compiled: a function (state, learn, epsilon) -> (state, StepLog) of
    `train.steps_per_iteration` actions per call, from one program of the K steps or, with
    `per_step` (`self.per_step` if None), from the one-step program called K times."""
    if not (self.per_step if per_step is None else per_step):
      return jax.jit(self.iterate)
    return functools.partial(_one_after_another, jax.jit(self.step),
                             self.config.train.steps_per_iteration)


def _one_after_another(step, k: int, state: TrainState, learn, epsilon
                       ) -> tuple[TrainState, StepLog]:
  """`k` calls of `step` (traced: written out in one program; jitted: k calls of its program),
  their logs stacked on a leading K axis."""
  logs = []
  for _ in range(k):
    state, log = step(state, learn, epsilon)
    logs.append(log)
  return state, jax.tree.map(lambda *steps: jnp.stack(steps), *logs)


def course_fingerprint(trainer: Trainer, calls: int = 2, iterate=None) -> str:
  """A short hash of the course `calls` calls of training take from `config.seed`, as
  mvcoba-train takes them: every call's StepLog, then the parameters and every tabletop's
  positions, bit for bit. A change of training's numerics by one float32 rounding changes it, and
  a run of 6000 actions then follows another course; `pretrained/mvcoba/course.json` holds the
  tiny preset's fingerprint at the commit that trained the shipped policy, and a test holds the
  two equal, so such a change retrains it. `iterate`: `trainer.compiled()`, if already built."""
  iterate = iterate or trainer.compiled()
  state = jax.jit(trainer.init)(jax.random.PRNGKey(trainer.config.seed))
  digest = hashlib.sha256()
  for _ in range(calls):
    state, log = iterate(state, jnp.bool_(True), jnp.float32(-1.0))
    for leaf in jax.tree.leaves(log):
      digest.update(np.asarray(leaf).tobytes())
  for leaf in jax.tree.leaves((state.params, state.task.env.sim.qpos)):
    digest.update(np.asarray(leaf).tobytes())
  return digest.hexdigest()[:16]
