"""The method registry: a new method is one entry, and networks, agent and export follow it."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from flax import nnx

from mvcoba_jax import export, methods
from mvcoba_jax.config import NetworkConfig, resolve
from mvcoba_jax.learner import agent, networks
from mvcoba_jax.sim.primitives import GRASP, PUSH


@pytest.fixture
def toy():
  """A push-only method that sees camera 2 and picks by max-Q, registered for one test."""
  method = methods.register(methods.Method('toy_push_cam2', fcns=(methods.Fcn((PUSH,), (1,)),),
                                           rule=methods.MAX_Q))
  yield method.name
  methods.unregister(method.name)


def test_a_registered_method_is_built_acts_and_exports(toy):
  assert toy in methods.names()
  assert methods.get(toy).views == (1,)
  config = NetworkConfig(method=toy, features=(8, 16), groups=4)
  net = networks.build_network(config, 4, nnx.Rngs(0))
  color = jax.random.uniform(jax.random.PRNGKey(1), (3, 2, 16, 16, 3))
  depth = jax.random.uniform(jax.random.PRNGKey(2), (3, 2, 16, 16)) * 0.05
  q = net(color, depth)
  assert q.shape == (3, 2, 4, 16, 16)
  assert (np.asarray(q[:, GRASP]) == networks.NO_ACTION).all()
  # Camera 1 is not an input: changing it changes nothing.
  np.testing.assert_array_equal(np.asarray(net(color.at[:, 0].set(0.0), depth)), np.asarray(q))
  action = agent.greedy_actions(q, jnp.ones(3, bool), methods.get(toy))
  assert (np.asarray(action.primitive) == PUSH).all()  # max-Q never picks a missing primitive
  assert export.action_rule(methods.get(toy))['name'] == 'max_q'


def test_a_new_rule_is_one_object_the_agent_asks():
  """A rule that always pushes and whose target looks at both primitives: acting, the target's
  max and model.json follow it without a line elsewhere."""
  push = methods.Rule('push', 'always push', lambda changed, best: jnp.zeros_like(changed, jnp.int32),
                      future_over_both=True, explores_primitive=False,
                      compares_primitives=False)
  method = methods.Method('toy_pusher', fcns=(methods.Fcn((PUSH, GRASP), (0,)),), rule=push)
  q = jnp.zeros((2, 2, 1, 4, 4)).at[:, GRASP, 0, 1, 2].set(5.0).at[:, PUSH, 0, 3, 0].set(1.0)
  action = agent.greedy_actions(q, jnp.array([True, False]), method)
  assert np.asarray(action.primitive).tolist() == [PUSH, PUSH]
  assert np.asarray(action.row).tolist() == [3, 3]
  train = resolve('default').train
  np.testing.assert_allclose(agent.future_value(q, jnp.array([True, False]), method, train), 5.0)
  assert export.action_rule(method)['primitive'] == 'always push'


def test_a_malformed_or_unknown_method_is_refused():
  with pytest.raises(ValueError, match="its rule must be a methods.Rule .* got 'sometimes'"):
    methods.Method('bad', fcns=(methods.Fcn((GRASP,), (0,)),), rule='sometimes')
  with pytest.raises(ValueError, match='score each primitive at most once'):
    methods.Method('bad', fcns=(methods.Fcn((GRASP,), (0,)), methods.Fcn((GRASP,), (1,))),
                   rule=methods.ALWAYS_GRASP)
  with pytest.raises(ValueError, match="unknown network method 'nope'; allowed: mvcoba"):
    methods.get('nope')


@pytest.mark.filterwarnings('ignore::DeprecationWarning')
def test_a_new_rule_reaches_the_exported_graph_and_one_it_cannot_trace_is_refused():
  """A toy rule decides inside the ONNX graph as the agent does; one written with integer `//`
  (a jitted jnp helper jax2onnx cannot trace) is refused, naming the method and why."""
  ort = pytest.importorskip('onnxruntime')
  pytest.importorskip('jax2onnx')
  from mvcoba_jax import perception
  pushes = methods.Rule('push', 'always push',
                        lambda changed, best: jnp.zeros(changed.shape, jnp.int32),
                        future_over_both=False, explores_primitive=False,
                        compares_primitives=False)
  where = methods.Rule('where', 'grasp after a change',
                       lambda changed, best: changed.astype(jnp.int32) * GRASP // 1,
                       future_over_both=False, explores_primitive=False,
                       compares_primitives=False)
  for name, rule in (('toy_pushes', pushes), ('toy_where', where)):
    methods.register(methods.Method(name, fcns=(methods.Fcn((PUSH, GRASP), (0,)),), rule=rule))
  try:
    config = resolve('tiny', ['network.method=toy_pushes'])
    model = networks.build_network(config.network, config.env.num_rotations, nnx.Rngs(0))
    session = ort.InferenceSession(export.onnx_model(config, model).SerializeToString(),
                                   providers=['CPUExecutionProvider'])
    side = perception.grid_size(config.perception, config.scene)
    color = jax.random.uniform(jax.random.PRNGKey(1), (1, 2, side, side, 3))
    depth = jax.random.uniform(jax.random.PRNGKey(2), (1, 2, side, side)) * 0.05
    action, value = session.run(['action', 'value'], {
        'color': np.asarray(color), 'depth': np.asarray(depth), 'changed': np.array([True])})
    want, score = agent.Decision.of(model.method, config).act(model(color, depth), depth,
                                                              jnp.array([True]))
    assert action[0].tolist() == [PUSH, int(want.rotation[0]), int(want.row[0]),
                                  int(want.col[0])]
    assert abs(float(value[0]) - float(score[0])) < 1e-4
    config = resolve('tiny', ['network.method=toy_where'])
    model = networks.build_network(config.network, config.env.num_rotations, nnx.Rngs(0))
    from mvcoba_jax.policy import PolicyError
    with pytest.raises(PolicyError, match='toy_where: its decision does not convert to ONNX .*'
                                          'cannot trace'):
      export.onnx_model(config, model)
  finally:
    for name in ('toy_pushes', 'toy_where'):
      methods.unregister(name)
