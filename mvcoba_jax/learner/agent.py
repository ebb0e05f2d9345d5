"""Acting and learning rules shared by every method: action choice, rewards, Q-learning targets,
the loss on executed actions and the optimiser (training and online evaluation share them).

Q maps are (B, 2, K, R, R): primitive (PUSH 0, GRASP 1), rotation, heightmap row and column.
"""
from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import optax
from flax import struct

from mvcoba_jax.config import Config, GripperConfig, TrainConfig
from mvcoba_jax.learner import networks, suppression
from mvcoba_jax.methods import Method
from mvcoba_jax.sim.contract import pixel_to_world
from mvcoba_jax.sim.primitives import GRASP, PUSH, Action  # noqa: F401  (agent.PUSH for callers)


@struct.dataclass
class PixelAction:
  """An action in heightmap terms: what the replay stores and the loss indexes."""
  primitive: jnp.ndarray  # (B,) int32
  rotation: jnp.ndarray  # (B,) int32
  row: jnp.ndarray  # (B,) int32
  col: jnp.ndarray  # (B,) int32


@dataclasses.dataclass(frozen=True)
class Decision:
  """How Q maps become an action, built once from the method and the settings its rule reads
  (`of`) and held by everything that acts: training explores through it (`explore`), the
  evaluation's actors, `Policy.act` and the exported graph act greedily through it (`act`,
  `maps`). A new setting of the rule is a field here, read nowhere else.

  With `suppress` (a suppressing method, CPG, or `network.suppress`) the rule compares
  `suppression.scores` of the Q maps: actions whose fingers cannot land, or pushes with nothing
  ahead, scored out (`push_room`, the gripper's fingers and the grid's `resolution` say where)."""
  method: Method
  suppress: bool
  resolution: float  # m per heightmap cell
  push_room: float
  gripper: GripperConfig

  @classmethod
  def of(cls, method: Method, config: Config) -> Decision:
    return cls(method=method, suppress=method.suppress or config.network.suppress,
               resolution=config.perception.heightmap_resolution,
               push_room=config.network.push_room, gripper=config.scene.gripper)

  def maps(self, q, depth):
    """The maps (B, 2, K, R, R) the rule compares and takes the argmax of: the Q maps `q` of
    every rotation, or where it suppresses their scores, for states of heightmaps `depth`
    (B, V, R, R)."""
    if not self.suppress:
      return q
    method = self.method
    return suppression.scores(q, surface_height(depth, method.views), self.resolution,
                              per_primitive=not method.rule.compares_primitives,
                              push_room=self.push_room, gripper=self.gripper)

  def act(self, q, depth, changed):
    """(action, score): the greedy action on Q maps `q` and the value its rule compared there.
    `changed` (B,): whether the previous action changed the scene (True before the first)."""
    return greedy(self.maps(q, depth), changed, self.method)

  def explore(self, q, depth, changed, occupied, epsilon, key):
    """(action, explored): `act`'s action, each replaced with probability `epsilon` by a random
    one (`epsilon_greedy`): how training acts."""
    return epsilon_greedy(self.maps(q, depth), changed, occupied, epsilon, key, self.method)


def greedy_actions(maps, changed, method: Method) -> PixelAction:
  """The rule's primitive at the argmax rotation and pixel of its maps (B, 2, K, R, R): Q maps,
  or `Decision.maps` of them. `changed` is whether the previous action changed the scene (True
  before the first action). The first maximum wins, in (rotation, row, col) order."""
  return greedy(maps, changed, method)[0]


def greedy(maps, changed, method: Method):
  """(`greedy_actions`, the maps' entry at each action (B,)). Written without jnp's
  take_along_axis, unravel_index and integer `//`, which jax2onnx cannot trace, so that the
  export traces it into the ONNX graph (`export.onnx_model`)."""
  b, _, k, r, _ = maps.shape
  flat = maps.reshape(b, 2, k * r * r)
  primitive = method.rule.pick(changed, flat.max(axis=-1))
  chosen = jnp.where((primitive == GRASP)[:, None], flat[:, GRASP], flat[:, PUSH])
  index = jnp.argmax(chosen, axis=-1).astype(jnp.int32)
  rotation, pixel = jax.lax.div(index, r * r), jax.lax.rem(index, r * r)
  action = PixelAction(primitive=primitive, rotation=rotation, row=jax.lax.div(pixel, r),
                       col=jax.lax.rem(pixel, r))
  # The map's entry at the argmax, not its max: a NaN there must reach the caller's checks.
  at = jnp.arange(k * r * r)[None] == index[:, None]
  return action, jnp.where(at, chosen, 0.0).sum(axis=-1)


def epsilon_greedy(maps, changed, occupied, epsilon, key, method: Method):
  """Greedy actions on the rule's `maps`, each replaced with probability epsilon by a random
  one; also says which.

  A random action keeps the rule's primitive (or draws it, `Rule.explores_primitive`) and draws a
  rotation and a pixel where something stands (`occupied`, (B, R, R); anywhere on an empty
  table). Uniform pixels land on bare table most of the time in a 10-object scene: wasted
  actions that teach only what the network learns in its first minutes. With them, a default
  run's training window ended at 64% while its greedy policy grasped 81%.
  """
  b, _, k, r, _ = maps.shape
  greedy = greedy_actions(maps, changed, method)
  k_explore, k_prim, k_rot, k_pixel = jax.random.split(key, 4)
  explore = jax.random.uniform(k_explore, (b,)) < epsilon
  primitive = greedy.primitive
  if method.rule.explores_primitive:
    primitive = jnp.where(explore, jax.random.randint(k_prim, (b,), 0, 2), primitive)
  mask = occupied.reshape(b, r * r)
  mask = mask | ~jnp.any(mask, axis=-1, keepdims=True)
  pixel = jax.random.categorical(k_pixel, jnp.where(mask, 0.0, -jnp.inf))
  pick = lambda random, best: jnp.where(explore, random, best).astype(jnp.int32)
  action = PixelAction(primitive=primitive.astype(jnp.int32),
                       rotation=pick(jax.random.randint(k_rot, (b,), 0, k), greedy.rotation),
                       row=pick(pixel // r, greedy.row), col=pick(pixel % r, greedy.col))
  return action, explore


def surface_height(depth, views: tuple[int, ...]):
  """(B, R, R) highest surface the method's views see in each heightmap cell of depth (B, V, R, R)."""
  return jnp.max(depth[:, jnp.asarray(views)], axis=1)


def to_world(action: PixelAction, depth, views: tuple[int, ...], resolution: float,
             workspace_half: float) -> Action:
  """World-frame primitive at the pixel of a grid of `resolution` m over the workspace; z is the
  highest surface the method's views see there."""
  x, y = pixel_to_world(action.row, action.col, resolution, workspace_half)
  z = surface_height(depth, views)[jnp.arange(depth.shape[0]), action.row, action.col]
  return Action(primitive=action.primitive, rotation=action.rotation, x=x, y=y, z=z)


@dataclasses.dataclass(frozen=True)
class Reward:
  """What an action earns: 1 for a grasp that lifts an object, `failed_grasp` for one that failed
  but changed the scene (else 0), 0.5 for a push that changed it, `no_change_push` for one that
  did not, plus `lost_object` for each object that left the workspace during it;
  `bootstrap_no_change`: whether an action that changed nothing bootstraps its target.
  Training's settings (`of`), which an online evaluation learns under too."""
  failed_grasp: float
  no_change_push: float
  lost_object: float
  bootstrap_no_change: bool

  @classmethod
  def of(cls, train: TrainConfig) -> Reward:
    return cls(failed_grasp=train.failed_grasp_reward, no_change_push=train.no_change_push_reward,
               lost_object=train.lost_object_reward,
               bootstrap_no_change=train.bootstrap_no_change)


def reward(primitive, grasp_success, changed, lost, paid: Reward):
  """Each action's reward (B,) as `paid` says; `lost`: the objects that left the workspace."""
  grasp_reward = jnp.where(grasp_success, 1.0, jnp.where(changed, paid.failed_grasp, 0.0))
  push_reward = jnp.where(changed, 0.5, paid.no_change_push)
  return jnp.where(primitive == GRASP, grasp_reward, push_reward) + paid.lost_object * lost


def future_value(q_next, changed, method: Method, train: TrainConfig):
  """max Q(s', a') over the primitive the rule picks at s' (over both for a rule whose target
  says so, `Rule.future_over_both`, and with `train.future_max='both'`), (B,)."""
  b = q_next.shape[0]
  best = q_next.reshape(b, 2, -1).max(axis=-1)
  if method.rule.future_over_both or train.future_max == 'both':
    return best.max(axis=-1)
  primitive = method.rule.pick(changed, best)
  return jnp.take_along_axis(best, primitive[:, None], axis=1)[:, 0]


def target_value(q_next, changed, done, rew, method: Method, train: TrainConfig):
  """y = r + gamma * max Q_target(s', a') over `future_value`'s primitives (0 where done)."""
  return bootstrap(future_value(q_next, changed, method, train), done, rew, train)


def bootstrap(future, done, rew, train: TrainConfig):
  """y = r + gamma * future, with no future where done."""
  return rew + train.gamma * jnp.where(done, 0.0, future)


def epsilon_at(actions, train: TrainConfig):
  """Linear decay from epsilon_start to epsilon_end over epsilon_decay_actions actions."""
  frac = jnp.clip(actions / max(train.epsilon_decay_actions, 1), 0.0, 1.0)
  return train.epsilon_start + frac * (train.epsilon_end - train.epsilon_start)


def optimizer(train: TrainConfig) -> optax.GradientTransformation:
  """SGD with momentum and weight decay, the paper's optimiser."""
  return optax.chain(optax.add_decayed_weights(train.weight_decay),
                     optax.sgd(train.learning_rate, momentum=train.momentum))


def sgd_step(loss, optimizer: optax.GradientTransformation, params, opt_state, *args):
  """One SGD step on `loss(params, *args) -> (value, aux)`, the one update of training and of
  online evaluation: the new parameters and optimiser state, the loss and its aux, and whether
  the loss and the new parameters are finite (both keep the old ones where not)."""
  (value, aux), grads = jax.value_and_grad(loss, has_aux=True)(params, *args)
  updates, opt_state = optimizer.update(grads, opt_state, params)
  params = optax.apply_updates(params, updates)
  finite = jnp.all(jnp.stack([jnp.all(jnp.isfinite(x)) for x in jax.tree.leaves(params)]))
  return params, opt_state, value, aux, jnp.isfinite(value) & finite


def quarter_turned(batch, turns, num_rotations: int):
  """`batch` (transitions with obs, next_obs, rotation, row, col) with each transition's states
  turned by `turns` (B,) quarter turns about the heightmap centre, each a quarter turn as
  `geometry.rotate_images(pi / 2)` makes (+x to +y), and its action with them: the pixel moves
  with the maps and the rotation index grows by a quarter of `num_rotations`. Rewards and flags
  are unchanged: a quarter-turned tabletop is the same tabletop."""
  b, side = turns.shape[0], batch.obs.depth.shape[-1]
  pick = lambda variants: jnp.stack(variants)[turns, jnp.arange(b)]
  turn = lambda x: pick([jnp.rot90(x, k=-i, axes=(2, 3)) for i in range(4)])
  row, col, last = batch.row, batch.col, side - 1
  return batch.replace(
      obs=jax.tree.map(turn, batch.obs), next_obs=jax.tree.map(turn, batch.next_obs),
      rotation=(batch.rotation + turns * (num_rotations // 4)) % num_rotations,
      row=pick([row, col, last - row, last - col]), col=pick([col, last - row, last - col, row]))


def executed_loss(q_maps, params, batch, y, valid, train: TrainConfig, num_rotations: int):
  """Huber loss of Q at each transition's executed pixel against its target `y` (N,), summed
  over the `valid` ones; also the TD errors (N,). `q_maps(params, obs, rotations (N, K))`.

  Summed, not averaged: each transition then moves the parameters as much as one of VPG's
  single-transition steps at the paper's learning rate. The mean made a batch of B worth one
  such step: learning per action was 16 times slower than VPG's (issue #4, first default run).
  With `train.grasp_symmetry` a grasp's target also labels its rotation turned half way, in
  the same forward (two rotations per transition).
  """
  t = train
  y = jax.lax.stop_gradient(y)
  weight = valid.astype(jnp.float32)
  if not t.grasp_symmetry:
    q = q_maps(params, batch.obs, batch.rotation[:, None])
    pred = networks.executed_q(q, batch.primitive, batch.row, batch.col)
    return jnp.sum(networks.huber_loss(pred, y, t.huber_delta) * weight), pred - y
  k = num_rotations
  turned = (batch.rotation + k // 2) % k
  q = q_maps(params, batch.obs, jnp.stack([batch.rotation, turned], axis=1))
  pred, pred_turned = (networks.executed_q(q[:, :, i:i + 1], batch.primitive, batch.row,
                                           batch.col) for i in (0, 1))
  is_grasp = (batch.primitive == GRASP).astype(jnp.float32)
  per = (networks.huber_loss(pred, y, t.huber_delta)
         + is_grasp * networks.huber_loss(pred_turned, y, t.huber_delta))
  return jnp.sum(per * weight), pred - y
