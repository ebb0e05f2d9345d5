"""Issue 69: MJX's reset alone and its reset and step in one program, traced and lowered, then
compiled; with `shared`, each scan's body (one MJX step and the pinning of parked slots) is one
jitted function both scans call, to see whether JAX or XLA then trace or compile it once.

  python docs/results/mjx-compile/shared_body.py          > plain.json
  python docs/results/mjx-compile/shared_body.py shared   > shared.json
"""
import json
import sys
import time

import jax
import jax.numpy as jnp
from mujoco import mjx

from mvcoba_jax import methods
from mvcoba_jax.config import resolve
from mvcoba_jax.learner import agent
from mvcoba_jax.learner.task import Task
from mvcoba_jax.sim import mjx_physics

shared = 'shared' in sys.argv
if shared:
  def stepped(model, data, ctrl, pin, parked, frames, extra=lambda d: None):
    @jax.jit
    def one(d, c, parked):
      return pin(mjx.step(model, d.replace(ctrl=c)), parked)
    def body(d, c):
      d = one(d, c, parked)
      return d, (d.qpos if frames else None, extra(d))
    data, (path, more) = jax.lax.scan(body, data, ctrl)
    at = path[jnp.asarray(frames)] if frames else jnp.zeros((0,) + data.qpos.shape, jnp.float32)
    return data, at, more
  mjx_physics.stepped = stepped

config = resolve('default', ['scene.backend=mjx'])
task = Task.build(config, (0, 1))
env = task.env
b = 8
keys = jax.random.split(jax.random.PRNGKey(0), b)
states = jax.eval_shape(jax.vmap(env.reset), keys)
q = jnp.zeros((b, 2, config.env.num_rotations, 112, 112))
def both(keys, states):
  fresh = jax.vmap(env.reset)(keys)
  depth = jnp.zeros((b, 2, 112, 112))
  pick = agent.greedy_actions(q, jnp.ones(b, bool), methods.get('mvcoba'))
  out, _ = jax.vmap(env.step)(states, task.to_world(pick, depth))
  return fresh, out
row = {'shared': shared}
for name, fn, args in (('reset', jax.vmap(env.reset), (keys,)), ('both', both, (keys, states))):
  t = time.perf_counter(); lowered = jax.jit(fn).lower(*args); lo = time.perf_counter() - t
  t = time.perf_counter(); lowered.compile(); co = time.perf_counter() - t
  row[name] = {'lower_s': round(lo, 1), 'compile_s': round(co, 1)}
  print(json.dumps(row), flush=True)
