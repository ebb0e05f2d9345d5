"""The method registry: a new method is one entry, and networks, agent and export follow it."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from flax import nnx

from mvcoba_jax import agent, export, methods, networks
from mvcoba_jax.config import NetworkConfig
from mvcoba_jax.sim.primitives import GRASP, PUSH


@pytest.fixture
def toy():
  """A push-only method that sees camera 2 and picks by max-Q, registered for one test."""
  method = methods.register(methods.Method('toy_push_cam2', fcns=(((PUSH,), (1,)),),
                                           rule='max_q'))
  yield method.name
  methods.unregister(method.name)


def test_a_registered_method_is_built_acts_and_exports(toy):
  assert toy in methods.names()
  assert networks.views_used(toy) == (1,)
  config = NetworkConfig(method=toy, features=(8, 16), groups=4)
  net = networks.build_network(config, 4, nnx.Rngs(0))
  color = jax.random.uniform(jax.random.PRNGKey(1), (3, 2, 16, 16, 3))
  depth = jax.random.uniform(jax.random.PRNGKey(2), (3, 2, 16, 16)) * 0.05
  q = net(color, depth)
  assert q.shape == (3, 2, 4, 16, 16)
  assert (np.asarray(q[:, GRASP]) == networks.NO_ACTION).all()
  # Camera 1 is not an input: changing it changes nothing.
  np.testing.assert_array_equal(np.asarray(net(color.at[:, 0].set(0.0), depth)), np.asarray(q))
  action = agent.greedy_actions(q, jnp.ones(3, bool), toy)
  assert (np.asarray(action.primitive) == PUSH).all()  # max-Q never picks a missing primitive
  assert export.action_rule(toy)['name'] == 'max_q'


def test_a_malformed_or_unknown_method_is_refused():
  with pytest.raises(ValueError, match="rule 'sometimes' is not one of change, max_q, grasp"):
    methods.Method('bad', fcns=(((GRASP,), (0,)),), rule='sometimes')
  with pytest.raises(ValueError, match='score each primitive at most once'):
    methods.Method('bad', fcns=(((GRASP,), (0,)), ((GRASP,), (1,))), rule='grasp')
  with pytest.raises(ValueError, match="unknown network method 'nope'; allowed: mvcoba"):
    networks.views_used('nope')
