"""Q-networks at toy sizes: shapes and wiring of every method, the rotation routine, and the
one-pixel loss."""
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest
from flax import nnx

from mvcoba_jax import methods
from mvcoba_jax.config import NetworkConfig
from mvcoba_jax.learner import agent, networks
from mvcoba_jax.learner.replay import Transition
from mvcoba_jax.methods import names as method_names
from mvcoba_jax.perception import Observation
from mvcoba_jax.sim import primitives
from mvcoba_jax.sim.geometry import rotate_images

SIDE, BATCH, ROTATIONS, VIEWS = 32, 2, 16, 4  # four views: MVP's camera poses
TINY = NetworkConfig(features=(8, 8), groups=4)
PADDED = dataclasses.replace(TINY, pad_to_diagonal=True)
SHARED = dataclasses.replace(TINY, features=(8, 8, 8), shared_stages=2)  # stems and a block


def _forward(config):
  """A jitted (state, color, depth, rotations) -> Q maps, the way the learner calls it."""
  graphdef, state = nnx.split(networks.build_network(config, ROTATIONS, nnx.Rngs(0)))
  return state, jax.jit(lambda state, color, depth, rotations=None:
                        nnx.merge(graphdef, state)(color, depth, rotations))


def _states(key, batch):
  kc, kd = jax.random.split(key)
  color = jax.random.uniform(kc, (batch, VIEWS, SIDE, SIDE, 3))
  depth = 0.05 * jax.random.uniform(kd, (batch, VIEWS, SIDE, SIDE))
  return color, depth


@pytest.fixture(scope='module')
def states():
  return _states(jax.random.key(1), BATCH)


@pytest.fixture(scope='module', params=method_names())
def method_maps(request, states):
  """Per method: Q maps of `states` and of the same states with view 1 changed."""
  state, forward = _forward(dataclasses.replace(TINY, method=request.param))
  color, depth = states
  q = forward(state, color, depth)
  q_other_view1 = forward(state, color.at[:, 1].set(1.0 - color[:, 1]), depth.at[:, 1].set(0.0))
  return request.param, np.asarray(q), np.asarray(q_other_view1)


def test_every_method_gives_finite_maps_of_every_rotation(method_maps):
  method, q, _ = method_maps
  assert q.shape == (BATCH, 2, ROTATIONS, SIDE, SIDE)
  assert np.isfinite(q).all()
  if method in ('grasp_only', 'mvp'):
    assert (q[:, primitives.PUSH] == networks.NO_ACTION).all()


def test_each_primitive_reads_only_its_camera(method_maps):
  method, q, q_other_view1 = method_maps
  changed = {p: not np.allclose(q[:, p], q_other_view1[:, p]) for p in (networks.PUSH,
                                                                        networks.GRASP)}
  expected = {'mvcoba': (True, True), 'mvcoba_2fcn': (False, True), 'vpg': (False, False),
              'grasp_only': (False, False), 'mvp': (False, True), 'cpg': (False, False)}[method]
  assert (changed[networks.PUSH], changed[networks.GRASP]) == expected
  assert methods.get(method).views == {'vpg': (0,), 'grasp_only': (0,), 'cpg': (0,),
                                         'mvp': (0, 1, 2, 3)}.get(method, (0, 1))


def test_fusion_keeps_the_highest_point_and_its_colour():
  """MVP's fusion: per cell the highest point any view saw, coloured by the views that saw it
  there; a view that saw nothing (0) neither lowers the height nor greys the colour."""
  depth = jnp.array([[[[0.0, 0.02]], [[0.05, 0.02]], [[0.0, 0.0]]]])  # (1, 3 views, 1, 2)
  color = jnp.zeros((1, 3, 1, 2, 3)).at[0, 0, 0, 0].set(0.5).at[0, 1, 0, 0].set(1.0)
  color = color.at[0, 0, 0, 1].set(0.2).at[0, 1, 0, 1].set(0.4)
  fused_color, fused_depth = networks.fuse_views(color, depth)
  np.testing.assert_allclose(np.asarray(fused_depth)[0, 0, 0], [0.05, 0.02])
  np.testing.assert_allclose(np.asarray(fused_color)[0, 0, 0], [[1.0] * 3, [0.3] * 3], atol=1e-6)


def test_primitive_channels_match_the_environment():
  assert (networks.PUSH, networks.GRASP) == (primitives.PUSH, primitives.GRASP) == (0, 1)


@pytest.mark.parametrize('field, value', [('method', 'dqn'), ('trunk', 'resnet50')])
def test_unknown_choices_name_the_allowed_ones(field, value):
  with pytest.raises(ValueError, match='allowed'):
    networks.build_network(dataclasses.replace(TINY, **{field: value}), ROTATIONS, nnx.Rngs(0))


@pytest.mark.parametrize('config', [TINY, SHARED], ids=['turned_inputs', 'turned_features'])
def test_one_rotation_equals_its_slice_of_all_rotations(states, config):
  state, forward = _forward(config)
  color, depth = states
  every = forward(state, color, depth)
  picked = jnp.array([[3], [10]])
  some = forward(state, color, depth, picked)
  assert some.shape == (BATCH, 2, 1, SIDE, SIDE)
  for b, k in enumerate(picked[:, 0]):
    np.testing.assert_allclose(some[b, :, 0], every[b, :, k], atol=1e-5)




def test_diagonal_padding_fits_the_diagonal_on_the_stem_grid():
  assert networks.diagonal_padding(112, 4) == 24  # 160 >= 158.4 cells, 40 patches
  assert networks.diagonal_padding(32, 4) == 8  # 48 >= 45.3
  assert networks.diagonal_padding(224, 32) == 48  # 320 >= 316.8, DenseNet's stride
  assert networks.diagonal_padding(112, 0) == 0


@pytest.mark.parametrize('unpadded', [TINY, SHARED], ids=['turned_inputs', 'turned_features'])
def test_padding_to_the_diagonal_keeps_the_corners(states, unpadded):
  """At 45 degrees an unpadded network cuts the corners off (Q = 0, whatever is there); padded,
  a corner's Q reads that corner."""
  color, depth = states
  corner_changed = (color.at[:, :, :4, :4].set(1.0), depth.at[:, :, :4, :4].set(0.05))
  eighth = jnp.full((BATCH, 1), ROTATIONS // 8)
  padded = dataclasses.replace(unpadded, pad_to_diagonal=True)
  for config, cut in ((unpadded, True), (padded, False)):
    state, forward = _forward(config)
    q = np.asarray(forward(state, color, depth, eighth))[:, :, 0, 0, 0]
    q_changed = np.asarray(forward(state, *corner_changed, eighth))[:, :, 0, 0, 0]
    assert (q == 0).all() == cut
    assert np.allclose(q, q_changed) == cut


def test_a_turn_through_nothing_returns_the_maps():
  """`turned` of the identity: a quarter turn gives the maps back exactly, padded or not; at 45
  degrees unpadded maps lose their corners and padded ones keep them (but for the outermost
  cell, which the two interpolations blend with the padding)."""
  row, col = np.mgrid[:SIDE, :SIDE] - (SIDE - 1) / 2
  maps = jnp.asarray(np.stack([np.sin(row / 5.0), np.cos(col / 4.0) + 2.0], -1)[None], jnp.float32)
  same = lambda x: x
  for pad in (0, 8):
    np.testing.assert_allclose(networks.turned(same, maps, jnp.array([np.pi / 2]), pad), maps,
                               atol=1e-5)
  eighth = jnp.array([np.pi / 4])
  assert (networks.turned(same, maps, eighth, 0)[0, :2, :2] == 0).all()
  np.testing.assert_allclose(networks.turned(same, maps, eighth, 8)[0, 1:3, 1:3],
                             maps[0, 1:3, 1:3], atol=0.02)


def test_shared_stages_run_once_per_state(states):
  """Turning the features after the stems and a block costs under half the FLOPs of turning
  the heightmaps, for all 16 rotations."""
  color, depth = states
  flops = {}
  for name, config in (('inputs', dataclasses.replace(SHARED, shared_stages=0)),
                       ('features', SHARED)):
    state, forward = _forward(config)
    flops[name] = forward.lower(state, color, depth).compile().cost_analysis()['flops']
  assert flops['features'] < 0.5 * flops['inputs'], flops


def test_shared_stages_leave_a_block_per_rotation():
  with pytest.raises(ValueError, match='network.shared_stages=2: at most 1'):
    dataclasses.replace(TINY, shared_stages=2)


def _quarter_turn(x, rows):
  """`x` turned as `rotate_images(x, pi / 2)` turns it (+x to +y), rows and cols at `rows`."""
  return jnp.rot90(x, k=-1, axes=(rows, rows + 1))


def test_padded_maps_turn_with_the_state(states):
  """Turning the heightmaps: a quarter turn of the state turns the padded maps of the rotation a
  quarter further by a quarter; the padding is cropped off centred, as it was added. (Turning
  features computed before the turn gives up this symmetry: the stems see the state unturned.)"""
  color, depth = states
  state, forward = _forward(PADDED)
  k = jnp.full((BATCH, 1), ROTATIONS // 8)
  q = np.asarray(forward(state, color, depth, k))
  q_turned = np.asarray(forward(state, _quarter_turn(color, 2), _quarter_turn(depth, 2),
                                k + ROTATIONS // 4))
  np.testing.assert_allclose(q_turned, _quarter_turn(q, 3), atol=1e-4)


def test_quarter_turned_transitions_score_as_they_were(states):
  """`train.quarter_turns`: a transition turned by 0-3 quarter turns has the executed Q it had
  under turned heightmaps (which hold the symmetry exactly): the action moved with the state.
  Four turns give the batch back. Turning features gives the symmetry up, so there the
  turned transitions are new data."""
  color, depth = states
  n = 4 * BATCH
  obs = Observation(color=jnp.tile(color, (4, 1, 1, 1, 1)), depth=jnp.tile(depth, (4, 1, 1, 1)),
                    seen=jnp.tile(depth > 0.02, (4, 1, 1, 1)))
  draws = jax.random.randint(jax.random.key(3), (4, n), 0, SIDE)
  batch = Transition(obs=obs, next_obs=obs, primitive=draws[0] % 2, rotation=draws[1] % ROTATIONS,
                     row=draws[2], col=draws[3], reward=jnp.zeros(n), done=jnp.zeros(n, bool),
                     changed=jnp.ones(n, bool), next_value=jnp.zeros(n))
  turns = jnp.repeat(jnp.arange(4), BATCH)
  turned = agent.quarter_turned(batch, turns, ROTATIONS)
  assert turned.rotation.tolist() == ((batch.rotation + 4 * turns) % ROTATIONS).tolist()
  again = turned
  for _ in range(3):
    again = agent.quarter_turned(again, turns, ROTATIONS)
  jax.tree.map(np.testing.assert_array_equal, again, batch)
  jax.tree.map(np.testing.assert_array_equal, agent.quarter_turned(batch, 0 * turns, ROTATIONS),
               batch)
  executed = {}
  for name, config in (('heightmaps', TINY), ('features', SHARED)):
    state, forward = _forward(config)
    executed[name] = [np.asarray(networks.executed_q(
        forward(state, b.obs.color, b.obs.depth, b.rotation[:, None]), b.primitive, b.row, b.col))
        for b in (batch, turned)]
  np.testing.assert_allclose(*executed['heightmaps'], atol=1e-4)
  assert np.abs(np.subtract(*executed['features'])[BATCH:]).max() > 1e-3


def test_rotating_by_zero_is_identity():
  images = jax.random.uniform(jax.random.key(0), (2, 9, 9, 3))
  np.testing.assert_array_equal(rotate_images(images, 0.0), images)


def test_quarter_turn_takes_plus_x_to_plus_y():
  images = jnp.zeros((1, 9, 9, 1)).at[0, 4, 6, 0].set(1.0)  # centre (4, 4), x = +2, y = 0
  turned = np.asarray(rotate_images(images, jnp.pi / 2))[0, :, :, 0]
  expected = np.zeros((9, 9))
  expected[6, 4] = 1.0  # x = 0, y = +2: row grows with y
  np.testing.assert_allclose(turned, expected, atol=1e-6)


def test_rotating_back_restores_the_interior():
  row, col = np.mgrid[:SIDE, :SIDE] - (SIDE - 1) / 2
  smooth = np.stack([np.sin(row / 5.0), np.cos(col / 4.0) * np.sin(row / 7.0)], axis=-1)
  images = jnp.asarray(smooth[None], jnp.float32)
  angles = jnp.array([0.7])
  back = np.asarray(rotate_images(rotate_images(images, angles), -angles))
  inside = np.hypot(row, col) < SIDE / 2 - 2
  np.testing.assert_allclose(back[0][inside], smooth[inside], atol=0.02)


def _loss(q_maps, actions, targets):
  primitive, row, col = actions
  return jnp.mean(networks.huber_loss(networks.executed_q(q_maps, primitive, row, col), targets))


def test_loss_gradient_only_at_the_executed_pixel():
  q_maps = jax.random.normal(jax.random.key(2), (3, 2, 1, SIDE, SIDE))
  actions = (jnp.array([0, 1, 1]), jnp.array([5, 0, 31]), jnp.array([7, 31, 2]))
  grad = np.asarray(jax.grad(_loss)(q_maps, actions, jnp.array([1.0, 0.0, 0.5])))
  expected = np.zeros(grad.shape, bool)
  for b, (p, r, c) in enumerate(zip(*actions)):
    expected[b, p, 0, r, c] = True
  assert (grad != 0).tolist() == expected.tolist()


def test_sgd_fits_a_fixed_batch():
  graphdef, params = nnx.split(networks.build_network(TINY, ROTATIONS, nnx.Rngs(0)))
  color, depth = _states(jax.random.key(3), 4)
  keys = jax.random.split(jax.random.key(4), 4)
  rotation = jax.random.randint(keys[0], (4, 1), 0, ROTATIONS)
  actions = (jax.random.randint(keys[1], (4,), 0, 2), jax.random.randint(keys[2], (4,), 0, SIDE),
             jax.random.randint(keys[3], (4,), 0, SIDE))
  targets = jnp.array([1.0, 0.5, 0.0, 1.0])
  tx = optax.sgd(1e-2, momentum=0.9)

  def loss(params):
    return _loss(nnx.merge(graphdef, params)(color, depth, rotation), actions, targets)

  @jax.jit
  def step(params, opt_state):
    value, grads = jax.value_and_grad(loss)(params)
    updates, opt_state = tx.update(grads, opt_state, params)
    return optax.apply_updates(params, updates), opt_state, value

  opt_state = tx.init(params)
  losses = []
  for _ in range(20):
    params, opt_state, value = step(params, opt_state)
    losses.append(float(value))
  assert losses[-1] < 0.5 * losses[0], losses


def test_densenet121_trunk_builds_with_the_right_shapes():
  """Abstractly: a concrete build compiles one initializer per kernel shape, ~30 s on 2 cores."""
  config = dataclasses.replace(TINY, trunk='densenet121')
  graphdef, state = nnx.split(nnx.eval_shape(
      lambda: networks.build_network(config, ROTATIONS, nnx.Rngs(0))))
  assert sum(x.size for x in jax.tree.leaves(state)) > 7e6  # DenseNet-121's body: ~7 M
  color = jax.ShapeDtypeStruct((BATCH, 2, SIDE, SIDE, 3), jnp.float32)
  depth = jax.ShapeDtypeStruct((BATCH, 2, SIDE, SIDE), jnp.float32)
  q = jax.eval_shape(lambda state, color, depth: nnx.merge(graphdef, state)(color, depth),
                     state, color, depth)
  assert q.shape == (BATCH, 2, ROTATIONS, SIDE, SIDE)
