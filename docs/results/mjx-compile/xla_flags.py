"""Issue 69: MJX's reset (the settling scan) at 8 tabletops compiled under the XLA_FLAGS of the
environment, and whether its result changes: prints the flags, trace-and-lower and compile
seconds, a second run, and a fingerprint of its settled states (objects in play, mean qpos).

  f=--xla_llvm_disable_expensive_passes=true
  for flags in $f "" $f ""; do
    JAX_ENABLE_COMPILATION_CACHE=false XLA_FLAGS="$flags" python docs/results/mjx-compile/xla_flags.py
  done > xla_flags.jsonl
"""
import json
import os
import time

import jax
import numpy as np

from mvcoba_jax.config import resolve
from mvcoba_jax.sim.tabletop import Tabletop

env = Tabletop(resolve(None, ['scene.backend=mjx']).tabletop)
keys = jax.random.split(jax.random.PRNGKey(0), 8)
start = time.perf_counter()
lowered = jax.jit(jax.vmap(env.reset)).lower(keys)
lower_s = time.perf_counter() - start
start = time.perf_counter()
program = lowered.compile()
compile_s = time.perf_counter() - start
jax.block_until_ready(program(keys))
start = time.perf_counter()
out = jax.block_until_ready(program(jax.random.split(jax.random.PRNGKey(1), 8)))
print(json.dumps({'flags': os.environ.get('XLA_FLAGS', ''), 'lower_s': round(lower_s, 1),
                  'compile_s': round(compile_s, 1), 'run_s': round(time.perf_counter() - start, 2),
                  'in_play': int(np.asarray(out.in_play).sum()),
                  'z_mean': float(np.asarray(out.sim.qpos).mean())}))
