"""Training throughput on 1 and 2 (virtual) devices: actions/s of the data-parallel train step.

Each device count runs in its own process (XLA fixes the device count at start-up), with the
same total batch, and prints JSON. On one CPU the "devices" share the same cores, so this checks
the sharded program's overhead rather than a speed-up; on a GPU host the devices are real.

  python benchmarks/scale.py [--config tiny] [--devices 1 2] [--iterations 3]
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent

WORKER = """
import json, sys, time
import jax, jax.numpy as jnp
from mvcoba_jax.config import resolve
from mvcoba_jax.learner import sharding
from mvcoba_jax.learner.training import Trainer
config = resolve(sys.argv[1])
iterations = int(sys.argv[2])
mesh = sharding.mesh()
trainer = Trainer(config, mesh)
state = sharding.place(jax.jit(trainer.init)(jax.random.PRNGKey(0)), mesh)
iterate = trainer.compiled()
args = (jnp.bool_(True), jnp.float32(-1.0))
t = time.perf_counter(); state, _ = jax.block_until_ready(iterate(state, *args))
compile_s = time.perf_counter() - t
t = time.perf_counter()
for _ in range(iterations):
  state, _ = jax.block_until_ready(iterate(state, *args))
wall = time.perf_counter() - t
actions = iterations * config.actions_per_call
print(json.dumps({'devices': len(jax.devices()), 'platform': jax.devices()[0].platform,
                  'num_envs': config.num_envs, 'actions_per_s': actions / wall,
                  'first_call_s': compile_s}))
"""


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--config', default='tiny')
  parser.add_argument('--devices', type=int, nargs='+', default=[1, 2])
  parser.add_argument('--iterations', type=int, default=3)
  args = parser.parse_args()
  rows = []
  for n in args.devices:
    env = dict(os.environ)
    env['XLA_FLAGS'] = f'{env.get("XLA_FLAGS", "")} --xla_force_host_platform_device_count={n}'
    out = subprocess.run([sys.executable, '-c', WORKER, args.config, str(args.iterations)],
                         cwd=ROOT, env=env, capture_output=True, text=True, check=True)
    rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
    print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
  base = rows[0]['actions_per_s']
  for r in rows:
    r['speedup_vs_first'] = r['actions_per_s'] / base
  print(json.dumps({'benchmark': 'scale', 'config': args.config, 'iterations': args.iterations,
                    'results': rows}, indent=1))


if __name__ == '__main__':
  main()
