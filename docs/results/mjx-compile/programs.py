"""Issue 69: trace + lower and XLA compile time of the two programs mvcoba-train compiles on MJX on
a CPU, `Trainer.init` and the one-step program `Trainer.compiled` calls K times, at 8 and 64
tabletops, from the state's shapes alone (nothing runs), the persistent cache off.

  JAX_ENABLE_COMPILATION_CACHE=false python docs/results/mjx-compile/programs.py 8 64
"""
import json
import sys
import time

import jax
import jax.numpy as jnp

from mvcoba_jax import runtime
from mvcoba_jax.config import resolve
from mvcoba_jax.learner.training import Trainer


def timed(fn, *args):
  start = time.perf_counter()
  lowered = jax.jit(fn).lower(*args)
  lower_s = time.perf_counter() - start
  start = time.perf_counter()
  lowered.compile()
  return round(lower_s, 1), round(time.perf_counter() - start, 1)


def main(batches):
  runtime.setup()
  for b in batches:
    trainer = Trainer(resolve(None, ['scene.backend=mjx', f'num_envs={b}']))
    key = jax.random.PRNGKey(0)
    state = jax.eval_shape(trainer.init, key)
    init = timed(trainer.init, key)
    step = timed(trainer.step, state, jnp.bool_(True), jnp.float32(-1.0))
    print(json.dumps({'batch': b, 'init_lower_s': init[0], 'init_compile_s': init[1],
                      'step_lower_s': step[0], 'step_compile_s': step[1]}), flush=True)


if __name__ == '__main__':
  main([int(b) for b in sys.argv[1:]])
