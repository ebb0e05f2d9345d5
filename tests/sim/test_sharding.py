"""Data parallelism: a 2-device run equals a 1-device run with the same total batch.

A whole training iteration (one lockstep action) takes the same actions with the same outcomes;
its loss agrees to 2%: the 2-device program steps one environment per device, and XLA's programs
for different batch sizes round the physics differently (about 1e-5 m after settling), which
reaches the heightmaps. The learner's update, run from one state, agrees to float precision.
"""
import os
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]

SCRIPT = """
import jax, jax.numpy as jnp, numpy as np
from mvcoba_jax import runtime
runtime.setup()
from mvcoba_jax.config import resolve
from mvcoba_jax.learner import sharding
from mvcoba_jax.learner.training import Trainer
assert len(jax.devices()) == 2, jax.devices()
config = resolve('tiny', ['train.steps_per_iteration=2'])  # the replay fills from step 2
trainer, sharded = Trainer(config), Trainer(config, sharding.mesh())
state = jax.jit(trainer.init)(jax.random.PRNGKey(0))
args = (jnp.bool_(True), jnp.float32(-1.0))
one, log_one = jax.jit(trainer.iterate)(jax.device_put(state, jax.devices()[0]), *args)
placed = sharding.place(state, sharding.mesh())
assert len(placed.task.env.sim.qpos.sharding.device_set) == 2
iterate = jax.jit(sharded.iterate)
two, log_two = iterate(placed, *args)
assert len(two.task.env.sim.qpos.sharding.device_set) == 2, 'environments left the mesh'
iterate(two, *args)  # the state comes back sharded as it went in: no second compilation
assert iterate._cache_size() == 1, 'the sharded step compiled again for its own output'
np.testing.assert_array_equal(np.asarray(log_one.grasp_success), np.asarray(log_two.grasp_success))
np.testing.assert_array_equal(np.asarray(log_one.primitive), np.asarray(log_two.primitive))
np.testing.assert_allclose(np.asarray(log_one.loss), np.asarray(log_two.loss), rtol=2e-2)
# The learner alone, from one state: the sharded update (gradients averaged over the devices)
# equals the single-device one. Compare what moved: parameters barely move in one step.
update = jax.jit(trainer.update)
key = jax.random.PRNGKey(5)
a, loss_a = update(jax.device_put(one, jax.devices()[0]), key)
b, loss_b = update(sharding.place(one, sharding.mesh()), key)
np.testing.assert_allclose(float(loss_a), float(loss_b), rtol=1e-4)
flat = lambda tree: np.concatenate([np.ravel(np.asarray(x, np.float64)) for x in jax.tree.leaves(tree)])
start = flat(one.params)
moved_a, moved_b = flat(a.params) - start, flat(b.params) - start
gap = np.linalg.norm(moved_a - moved_b) / np.linalg.norm(moved_a)
assert np.linalg.norm(moved_a) > 0 and gap < 1e-3, gap
print('EQUIVALENT', float(loss_a), float(loss_b), gap)
"""


def test_two_virtual_devices_match_one_device():
  env = dict(os.environ, XLA_FLAGS='--xla_force_host_platform_device_count=2')
  result = subprocess.run([sys.executable, '-c', SCRIPT], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=1800)
  assert result.returncode == 0, result.stderr[-3000:]
  assert 'EQUIVALENT' in result.stdout
