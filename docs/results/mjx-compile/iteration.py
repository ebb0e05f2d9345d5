"""Issue 69: the whole training iteration (`Trainer.iterate`) at B tabletops, traced and lowered,
compiled, and run (`REPEATS` times, 3 unless set) after a fresh `Trainer.init`; `written` as the
CPU runs it (the K steps one after the other), `scan` as accelerators do (one `lax.scan` of K
steps), forced here on the CPU to see what each form costs. One JSON line.

  python docs/results/mjx-compile/iteration.py written|scan native|mjx B [KEY=VALUE ...]
"""
import json
import os
import sys
import time

import jax
import jax.numpy as jnp

from mvcoba_jax.config import resolve
from mvcoba_jax.learner.training import Trainer

form, backend, batch = sys.argv[1], sys.argv[2], int(sys.argv[3])
extra = sys.argv[4:]
config = resolve('default', [f'scene.backend={backend}', f'num_envs={batch}'] + extra)
trainer = Trainer(config)
if form == 'scan':
  def iterate(self, state, learn, epsilon):
    k = self.config.train.steps_per_iteration
    return jax.lax.scan(lambda s, _: self.step(s, learn, epsilon), state, None, length=k)
  Trainer.iterate = iterate
start = time.perf_counter()
state = jax.block_until_ready(jax.jit(trainer.init)(jax.random.PRNGKey(0)))
init_s = time.perf_counter() - start
args = (jnp.bool_(True), jnp.float32(-1.0))
start = time.perf_counter()
lowered = jax.jit(trainer.iterate).lower(state, *args)
lower_s = time.perf_counter() - start
start = time.perf_counter()
program = lowered.compile()
compile_s = time.perf_counter() - start
walls = []
for _ in range(int(os.environ.get('REPEATS', 3))):
  start = time.perf_counter()
  state, _ = jax.block_until_ready(program(state, *args))
  walls.append(time.perf_counter() - start)
k = config.train.steps_per_iteration
print(json.dumps({'form': form, 'backend': backend, 'batch': batch, 'extra': extra,
                  'init_s': round(init_s, 1), 'lower_s': round(lower_s, 1),
                  'compile_s': round(compile_s, 1), 'walls': [round(w, 2) for w in walls],
                  'actions_per_s': round(batch * k / min(walls[1:]), 3)}), flush=True)
