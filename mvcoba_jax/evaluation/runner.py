"""Evaluation of a policy on test cases: every (case, run) pair of a suite in lockstep, the
trained network frozen and greedy (one compiled loop) or going on learning in every run
(`Online`, the paper's test protocol), each an `Actor` the loop plays alike.

Each run starts from its case (padded to the scene's object slots) with a few millimetres and
degrees of placement noise, so the n runs of a case differ as real resets do. A run ends when
every object is picked, when more than `env.max_failures` consecutive actions fail, or at the action
cap; finished runs stop counting while the batch steps on in lockstep (on emptied tables, which
cost a fraction of a cluttered one) until the runs still going move to a smaller batch
(benchmarks/finished_runs.py), and the loop stops as soon as every run has finished.
"""
from __future__ import annotations

import functools
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx, struct

from mvcoba_jax import perception
from mvcoba_jax.config import Config
from mvcoba_jax.evaluation import metrics
from mvcoba_jax.learner import agent, networks
from mvcoba_jax.learner import replay as replay_lib
from mvcoba_jax.learner.task import Outcome, State, Task
from mvcoba_jax.sim import contract
from mvcoba_jax.sim.tabletop import Layout, where_envs
from mvcoba_jax.suites.cases import start

class Actor:
  """What an evaluation plays, one signature for every protocol and baseline: `init(obs)` gives
  its per-run state (the carry; None when it keeps none), `act(carry, obs, changed, active,
  keys, failed)` each run's action and the carry after it, `observe(carry, transition, done,
  active)` the carry once the action's transition is known (`task.transition`). `keys` (N, 2)
  keep each run's draws independent of its batch; `failed` is each run's failed actions since
  the scene last changed, (N, F, 4: primitive, rotation, row, col), and how many it holds (N,).
  `learns`: `act` takes an SGD step, which XLA's CPU backend runs faster from a loop on the
  host (`advance_on_host`). Actors are hashed by identity: the compiled loop keys on them."""
  learns = False

  def init(self, obs: perception.Observation):
    return None

  def act(self, carry, obs, changed, active, keys, failed):
    raise NotImplementedError

  def observe(self, carry, transition: replay_lib.Transition, done, active):
    return carry


class Frozen(Actor):
  """An actor that keeps nothing between actions: `choose(obs, changed, keys, failed)` ->
  agent.PixelAction (the trained network's greedy rule, or a baseline)."""

  def __init__(self, choose: Callable):
    self.choose = choose

  def act(self, carry, obs, changed, active, keys, failed):
    return self.choose(obs, changed, keys, failed), carry


@struct.dataclass
class Trace:
  """What each run saw and did, step by step (N, T, ...): for pictures of the runs and for
  tracing where objects leave the workspace."""
  color: jnp.ndarray  # (N, T, V, R, R, 3) uint8: every view's colour heightmap before the action
  object_xyz: jnp.ndarray  # (N, T, M, 3): every object slot's centre before the action
  left_workspace: jnp.ndarray  # (N, T, M) bool: the objects that left during the action
  primitive: jnp.ndarray  # (N, T) int32
  rotation: jnp.ndarray
  row: jnp.ndarray
  col: jnp.ndarray
  grasp_success: jnp.ndarray  # (N, T) bool
  active: jnp.ndarray  # (N, T) bool: the run had not finished, so the step counts
  # For videos (`video.py`; `evaluate` fills them): qpos at the env's `frames` points of each
  # primitive (F may be 0), the slots' colours and the occluders' poses.
  frames: jnp.ndarray | None = None  # (N, T, F, nq)
  slot_color: jnp.ndarray | None = None  # (N, T, M, 3) uint8
  mocap_pos: jnp.ndarray | None = None  # (N, T, K, 3)
  mocap_quat: jnp.ndarray | None = None  # (N, T, K, 4)


@struct.dataclass
class Runs:
  """Per-run counters (N,), and the step-by-step `trace` when it was recorded."""
  actions: jnp.ndarray
  grasp_attempts: jnp.ndarray
  grasp_successes: jnp.ndarray
  picked: jnp.ndarray
  lost: jnp.ndarray
  objects: jnp.ndarray
  finished: jnp.ndarray
  completed: jnp.ndarray
  # Per object slot (N, M + 1, 5), the last row for actions at no object: objects in play at the
  # start, objects picked, grasps aimed at it, those that lifted something, pushes that moved
  # it most (`_by_slot`).
  by_slot: jnp.ndarray
  # Failed actions since the scene last changed (N, F, 4: primitive, rotation, row, col), the
  # first `tried` of them, and the actions that repeated one of them exactly.
  failed: jnp.ndarray
  tried: jnp.ndarray
  repeated_failures: jnp.ndarray
  trace: Trace | None = None
  carry: Any = None  # the actor's per-run state as the run ended (online: its `Learner`)


@struct.dataclass
class Learner:
  """Online evaluation's learning, per run (B, ...): the run's own parameters and optimiser
  state, and its last transition, which waits for the acting forward of its next state to value
  it (as `train.target='acting'` does in training)."""
  params: Any
  opt_state: Any
  pending: replay_lib.Transition
  pending_valid: jnp.ndarray  # (B,) bool


class Online(Actor):
  """A trained network that goes on learning in every run, the test protocol of VPG and the
  MV-COBA authors: each run starts from the trained parameters and, after each action, takes one
  SGD step on its previous transition with the loss, targets and optimiser of `config.train`.
  Every run holds its own copy (stacked along the run axis), so a run learns from its own
  transitions only; a finished run learns no more."""
  learns = True

  def __init__(self, model: networks.QNetwork, config: Config):
    self.graphdef, self.params = nnx.split(model)
    self.config = config
    self.method = model.method
    self.decision = agent.Decision.of(model.method, config)
    self.optimizer = agent.optimizer(config.train)

  def q_maps(self, params, obs: perception.Observation, rotations=None):
    return nnx.merge(self.graphdef, params)(obs.color, obs.depth, rotations)

  def init(self, obs: perception.Observation) -> Learner:
    """Every run of the batch (B,) with the trained parameters and nothing to learn yet."""
    n = obs.depth.shape[0]
    params = jax.tree.map(lambda x: jnp.broadcast_to(x, (n,) + x.shape), self.params)
    return Learner(params=params, opt_state=jax.vmap(self.optimizer.init)(params),
                   pending=replay_lib.Transition.empty(obs),
                   pending_valid=jnp.zeros(n, jnp.bool_))

  def act(self, learner: Learner, obs, changed, active, keys, failed):
    """Each run's greedy action on its own Q maps; the forward also values the state its
    waiting transition led to, and each active run learns from that transition (`learn`).

    The runs' forwards go one after the other (`lax.map`), each with its own weights: vmapped
    over the weights, XLA's CPU backend runs them as grouped convolutions, 3 times slower
    (0.85 s against 2.7 s for 18 runs of the default preset)."""
    one = lambda args: self.q_maps(args[0], jax.tree.map(lambda x: x[None], args[1]))[0]
    q = jax.lax.map(one, (learner.params, obs))
    action, _ = self.decision.act(q, obs.depth, changed)
    return action, self.learn(learner, q, changed, active)

  def learn(self, learner: Learner, q, changed, active) -> Learner:
    """One SGD step per run on its waiting transition, valued by `q` of the state it led to;
    runs not `active`, with nothing waiting or with a non-finite step keep their parameters.
    Vmapped over the runs: in a `lax.map` loop body the update runs 6 times slower."""
    t = self.config.train
    pending = learner.pending
    y = agent.bootstrap(agent.future_value(q, changed, self.method, t), pending.done,
                        pending.reward, t)

    def step(params, opt_state, transition, y):
      loss = lambda p, one, y: agent.executed_loss(self.q_maps, p, one, y, jnp.ones(1, bool),
                                                   t, self.config.env.num_rotations)
      params, opt_state, _, _, sound = agent.sgd_step(
          loss, self.optimizer, params, opt_state, jax.tree.map(lambda x: x[None], transition),
          y[None])
      return params, opt_state, sound

    params, opt_state, sound = jax.vmap(step)(learner.params, learner.opt_state, pending, y)
    ok = learner.pending_valid & active & sound
    keep = lambda new, old: jax.tree.map(
        lambda a, b: jnp.where(ok.reshape(ok.shape + (1,) * (a.ndim - 1)), a, b), new, old)
    return learner.replace(params=keep(params, learner.params),
                           opt_state=keep(opt_state, learner.opt_state))

  def observe(self, learner: Learner, transition: replay_lib.Transition, done, active
              ) -> Learner:
    """The transition each active run just made waits to be learned from once its next state
    is valued; a run that this action finished has no next state to value, and learns no more."""
    waits = active & ~done
    return learner.replace(pending=where_envs(waits, transition, learner.pending),
                           pending_valid=waits)


@struct.dataclass
class Batch:
  """The evaluation loop's carry: the runs in the batch (B,), each run's task and counts, and
  the lockstep action count."""
  state: State
  runs: Runs
  keys: jnp.ndarray  # (B, 2)
  t: jnp.ndarray  # int32: lockstep actions taken
  carry: Any = None  # the actor's per-run state (`Actor.init`)


@functools.partial(jax.jit, static_argnames=('task', 'max_actions', 'record'))
def begin(task: Task, layouts: Layout, keys, max_actions: int, record: bool) -> Batch:
  """Every run settled at its start, counters at zero (and an empty trace with `record`)."""
  env = task.env
  states, k_loop = start(env, layouts, keys)
  begun = task.begin(states)
  obs = begun.obs
  n = layouts.in_play.shape[0]
  zeros = jnp.zeros(n, jnp.int32)
  runs = Runs(actions=zeros, grasp_attempts=zeros, grasp_successes=zeros, picked=zeros,
              lost=zeros, objects=jnp.sum(states.in_play, axis=1, dtype=jnp.int32),
              finished=jnp.zeros(n, bool), completed=jnp.zeros(n, bool),
              by_slot=jnp.pad(states.in_play.astype(jnp.int32)[..., None],
                              ((0, 0), (0, 1), (0, 4))),
              failed=jnp.zeros((n, env.config.env.max_failures + 1, 4), jnp.int32),
              tried=zeros, repeated_failures=zeros)
  if record:
    nothing = agent.PixelAction(zeros, zeros, zeros, zeros)
    shapes = jax.eval_shape(lambda s, a: jax.vmap(env.step)(s, a)[1], states,
                            task.to_world(nothing, obs.depth))
    step = _snapshot(env, obs, states, nothing,
                     jax.tree.map(lambda x: jnp.zeros(x.shape, x.dtype), shapes), runs.finished)
    runs = runs.replace(trace=jax.tree.map(
        lambda x: jnp.zeros((n, max_actions) + x.shape[1:], x.dtype), step))
  return Batch(state=begun, runs=runs, keys=k_loop, t=jnp.int32(0))


def _snapshot(env, obs, states, action: agent.PixelAction, info, active) -> Trace:
  """One step of every run (B, ...), as the trace keeps it."""
  return Trace(color=perception.color_to_uint8(obs.color),
               object_xyz=jax.vmap(env.object_positions)(states),
               left_workspace=info.left_workspace, primitive=action.primitive,
               rotation=action.rotation, row=action.row, col=action.col,
               grasp_success=info.grasp_success, active=active, frames=info.frames,
               slot_color=perception.color_to_uint8(states.color),
               mocap_pos=states.sim.mocap_pos, mocap_quat=states.sim.mocap_quat)


@functools.partial(jax.jit, static_argnames=('task', 'actor', 'max_actions', 'record',
                                             'progress'))
def advance(task: Task, actor: Actor, batch: Batch, max_actions: int, record: bool, progress,
            until, retired) -> Batch:
  """Lockstep actions until every run of the batch has finished, the action cap, or no more than
  `until` runs still going; `retired`: the finished runs outside this batch (for `progress`)."""
  def going(batch: Batch):
    still = jnp.sum(~batch.runs.finished)
    return (still > 0) & (still > until) & (batch.t < max_actions)

  return jax.lax.while_loop(
      going, lambda b: lockstep(task, actor, b, record, progress, retired), batch)


def advance_on_host(task: Task, actor: Actor, batch: Batch, max_actions: int, record: bool,
                    progress, until, retired) -> Batch:
  """`advance` with its loop on the host, one compiled lockstep action per call: what a learning
  actor runs on a CPU, where XLA runs an SGD update inside a loop body several times slower than
  outside one (docs/design.md; training writes its steps out for the same reason)."""
  while True:
    still = int(jnp.sum(~batch.runs.finished))
    if not (still > 0 and still > until and int(batch.t) < max_actions):
      return batch
    batch = _lockstep(task, actor, batch, record, progress, retired)


def lockstep(task: Task, actor: Actor, batch: Batch, record: bool, progress,
             retired) -> Batch:
  """One lockstep action of every run of the batch; `retired`: the finished runs outside this
  batch (for `progress`)."""
  before, runs = batch.state, batch.runs
  obs = before.obs
  keys, k_act = jax.vmap(jax.random.split, out_axes=1)(batch.keys)
  active = ~runs.finished
  action, carry = actor.act(batch.carry, obs, before.changed, active, k_act,
                            (runs.failed, runs.tried))
  after, out = task.step(before, action)
  carry = actor.observe(carry, task.transition(obs, after, action, out), out.done, active)
  info = out.info
  count = lambda total, x: total + jnp.where(active, x, 0).astype(jnp.int32)
  is_grasp = action.primitive == agent.GRASP
  picked = count(runs.picked, info.picked)
  failed, tried, repeated = _repeats(runs, action, out, active)
  by_slot = runs.by_slot + jnp.where(
      active[:, None, None],
      jax.vmap(functools.partial(_by_slot, task.env))(before.env, after.env,
                                                      task.to_world(action, obs.depth), info),
      0)
  runs = runs.replace(
      actions=count(runs.actions, 1), grasp_attempts=count(runs.grasp_attempts, is_grasp),
      grasp_successes=count(runs.grasp_successes, info.grasp_success), picked=picked,
      lost=count(runs.lost, info.lost), finished=runs.finished | out.done,
      completed=runs.completed | (active & out.cleared & (picked == runs.objects)),
      failed=failed, tried=tried, repeated_failures=count(runs.repeated_failures, repeated),
      by_slot=by_slot)
  if record:
    runs = runs.replace(trace=jax.tree.map(
        lambda buf, x: buf.at[:, batch.t].set(x), runs.trace,
        _snapshot(task.env, obs, before.env, action, info, active)))
  if progress is not None:
    jax.debug.callback(progress, batch.t + 1, retired + jnp.sum(runs.finished))
  # A finished run steps on with its table emptied, so the batch waits for the others at
  # a fraction of the cost; nothing it does is counted.
  after = where_envs(active, after, before).replace(
      env=where_envs(runs.finished, jax.vmap(task.env.emptied)(after.env), after.env))
  return Batch(state=after, runs=runs, keys=keys, t=batch.t + 1, carry=carry)


_lockstep = jax.jit(lockstep, static_argnames=('task', 'actor', 'record', 'progress'))


PUSHED = 0.01  # m: a push moved an object when it slid this far


def _by_slot(env, before, after, world, info):
  """One action's counts per object slot of one run (M + 1, 5), as `Runs.by_slot` sums them. A
  grasp is aimed at the object it lifted (the one under its point if it lifted several), or
  when it lifted none at the object under its point (`Tabletop.object_at`); a push at the
  object it moved farthest, when that is `PUSHED` or more; either at the last row when at none."""
  m = before.in_play.shape[0]
  picked = before.in_play & ~after.in_play & ~info.left_workspace
  under = env.object_at(before, jnp.stack([world.x, world.y, world.z]))
  lifted_under = (under >= 0) & picked[jnp.maximum(under, 0)]
  grasped = jnp.where(info.grasp_success & ~lifted_under, jnp.argmax(picked), under)
  slid = jnp.linalg.norm(env.object_positions(after)[:, :2] - env.object_positions(before)[:, :2],
                         axis=-1)
  slid = jnp.where(before.in_play, slid, 0.0)
  pushed = jnp.where(jnp.max(slid) >= PUSHED, jnp.argmax(slid), -1)
  is_grasp = world.primitive == agent.GRASP
  target = jnp.where(is_grasp, grasped, pushed)
  row = jnp.where(target < 0, m, target)
  counts = jnp.stack([0, 0, is_grasp, is_grasp & info.grasp_success, ~is_grasp]).astype(jnp.int32)
  return (jnp.zeros((m + 1, 5), jnp.int32).at[row].set(counts)
          .at[:m, 1].add(picked.astype(jnp.int32)))


def _repeats(runs: Runs, action: agent.PixelAction, out: Outcome, active):
  """The failed actions since the scene last changed, with this one's outcome, and whether
  this action repeated one of them exactly (B,). A run ends after `env.max_failures` + 1 failed
  actions in a row, so the list never holds more."""
  this = jnp.stack([action.primitive, action.rotation, action.row, action.col], axis=-1)
  slots = jnp.arange(runs.failed.shape[1])
  repeated = jnp.any((slots < runs.tried[:, None])
                     & jnp.all(runs.failed == this[:, None], axis=-1), axis=-1)
  failed_here = contract.failed(action.primitive == agent.GRASP, out.info.grasp_success,
                                out.changed, jnp)
  kept = failed_here & ~out.changed & active
  at = jnp.minimum(runs.tried, slots.size - 1)
  failed = jnp.where(kept[:, None, None],
                     runs.failed.at[jnp.arange(this.shape[0]), at].set(this), runs.failed)
  tried = jnp.where(active & out.changed, 0,
                    jnp.where(kept, jnp.minimum(runs.tried + 1, slots.size), runs.tried))
  return failed, tried, repeated & active


def evaluate(task: Task, actor: Actor, layouts: Layout, keys, max_actions: int,
             record: bool = False,
             progress: Callable[[jnp.ndarray, jnp.ndarray], None] | None = None,
             smallest: int = 8) -> Runs:
  """Plays `actor` from each layout (N,) with its key (N,); returns the counters. An `Online`
  actor goes on learning in every run, each from its own transitions.

  The runs step in lockstep in one compiled loop. Once no more than half of the batch is still
  going, those runs go on in a batch half the size (padded with finished runs), down to
  `smallest`: finished runs would otherwise cost the network and the cameras as much as live
  ones. A run's actions depend only on its own layout and key, but the network rounds
  differently at each batch size, so a knife-edge choice can differ from a run in another
  batch. With `record`, `Runs.trace` holds every step's heightmaps and action (memory grows
  with N x max_actions x views x R^2 x 3 bytes). `progress(actions_done, runs_finished)` is
  called on the host after every lockstep action: a large suite can take an hour on a CPU.
  """
  batch = begin(task, layouts, keys, max_actions, record)
  batch = batch.replace(carry=jax.jit(actor.init)(batch.state.obs))
  n = layouts.in_play.shape[0]
  size, members, runs = n, jnp.arange(n), batch.runs.replace(carry=batch.carry)
  loop = advance_on_host if actor.learns and jax.default_backend() == 'cpu' else advance
  while True:
    until = size // 2 if size // 2 >= smallest else -1
    batch = loop(task, actor, batch, max_actions, record, progress, until, n - size)
    runs = jax.tree.map(lambda whole, part: whole.at[members].set(part), runs,
                        batch.runs.replace(carry=batch.carry))
    going = int(jnp.sum(~batch.runs.finished))
    if not going or int(batch.t) >= max_actions:
      return runs
    while size // 2 >= max(going, smallest):
      size //= 2
    keep = jnp.argsort(batch.runs.finished, stable=True)[:size]  # every run still going first
    members = members[keep]
    batch = jax.tree.map(lambda x: x[keep] if jnp.ndim(x) else x, batch)


def run_logs(runs: Runs, task: Task) -> list[metrics.RunLog]:
  """Host-side per-run records for the metrics, of runs of `task`."""
  slot_shapes = task.env.scene.index.slot_shapes
  r = jax.tree.map(lambda x: x.tolist(), runs.replace(trace=None, carry=None))
  return [metrics.RunLog(
      actions=r.actions[i], grasp_attempts=r.grasp_attempts[i],
      grasp_successes=r.grasp_successes[i], objects=r.objects[i], picked=r.picked[i],
      lost=r.lost[i], completed=r.completed[i], repeated_failures=r.repeated_failures[i],
      shapes=metrics.shape_counts(r.by_slot[i], slot_shapes)) for i in range(len(r.actions))]


def losses(trace: Trace, names: list[str], task: Task) -> list[dict]:
  """Every object that left the workspace in a recorded evaluation, with the action it left in.

  Host side, from `Runs.trace`; `names[i]` names run i. Where the object was when the action
  began, how far from the gripper's target and from the workspace's border, tells a grasp that
  drops its object from a push that shoves a neighbour over the edge.
  """
  half = task.env.config.scene.workspace_half
  trace = jax.device_get(trace)
  left = np.asarray(trace.left_workspace) & np.asarray(trace.active)[..., None]
  records = []
  for run, t, slot in zip(*np.nonzero(left)):
    x, y = contract.pixel_to_world(trace.row[run, t], trace.col[run, t],
                          task.perception.heightmap_resolution, half)
    xyz = np.asarray(trace.object_xyz[run, t, slot], float)
    records.append({
        'run': names[run], 'action': int(t), 'slot': int(slot),
        'primitive': 'grasp' if trace.primitive[run, t] == agent.GRASP else 'push',
        'grasp_success': bool(trace.grasp_success[run, t]),
        'object_xyz': [round(float(v), 4) for v in xyz],
        'gripper_xy': [round(float(x), 4), round(float(y), 4)],
        'distance_to_gripper': round(float(np.hypot(xyz[0] - x, xyz[1] - y)), 4),
        'margin_to_border': round(float(half - np.max(np.abs(xyz[:2]))), 4)})
  return records


def greedy_actor(q_maps: Callable, decision: agent.Decision, no_repeat: bool = False) -> Frozen:
  """A trained network, frozen and greedy: `q_maps(obs)` -> (N, 2, K, R, R), its maps' rule
  `decision`'s. With `no_repeat` it never takes a failed action of its run again while nothing
  has changed: the next best one."""

  def choose(obs, changed, keys, failed):
    maps = decision.maps(q_maps(obs), obs.depth)
    if no_repeat:
      maps = without(maps, *failed)
    return agent.greedy_actions(maps, changed, decision.method)
  return Frozen(choose)


def without(maps, failed, tried):
  """`maps` (N, 2, K, R, R) with the first `tried` (N,) of each run's `failed` actions (N, F, 4)
  scored -inf."""
  runs = jnp.arange(maps.shape[0])
  for j in range(failed.shape[1]):
    p, k, r, c = (failed[:, j, i] for i in range(4))
    maps = maps.at[runs, p, k, r, c].set(jnp.where(j < tried, -jnp.inf, maps[runs, p, k, r, c]))
  return maps


def heuristic_actor(num_rotations: int) -> Frozen:
  """A baseline that needs no training: grasp the highest cell at a random rotation; after an
  action that changed nothing, push from the highest cell in a random direction."""
  def choose(obs, changed, keys, failed):
    height = jnp.max(obs.depth, axis=1)  # (N, R, R) over both views
    n, r, _ = height.shape
    cell = jnp.argmax(height.reshape(n, -1), axis=-1)
    row, col = jnp.unravel_index(cell, (r, r))
    rotation = jax.vmap(lambda k: jax.random.randint(k, (), 0, num_rotations))(keys)
    return agent.PixelAction(primitive=jnp.where(changed, agent.GRASP, agent.PUSH).astype(jnp.int32),
                             rotation=rotation.astype(jnp.int32), row=row.astype(jnp.int32),
                             col=col.astype(jnp.int32))
  return Frozen(choose)
