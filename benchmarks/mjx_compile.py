"""Where MJX's compile time goes: each part of the training step compiled alone at B tabletops
(issue 69): the primitive's physics (`Tabletop.step`, one loop of MJX steps), a fresh drop
(`Tabletop.reset`: the drop's settling loop), both cameras' rays and heightmaps
(`Task.observe`), the reset and the step as two loops in one program (`reset_and_step`) and as
the training step runs them, one loop run twice (`step_and_settle`), on the backend asked for,
each with its tracing and lowering time, XLA's compile time and one run after it (the whole
training iteration's compile: `benchmarks/train.py`). Prints one JSON object.

  python benchmarks/mjx_compile.py [--config default] [--backend mjx] [--batch 8]
"""
from __future__ import annotations

import argparse
import json
import time

import jax

from mvcoba_jax import methods
from mvcoba_jax.config import resolve
from mvcoba_jax.learner import agent
from mvcoba_jax.learner.task import Task


def compiled(fn, *args) -> dict:
  """Seconds to trace and lower, to compile, and of one run after it."""
  start = time.perf_counter()
  lowered = jax.jit(fn).lower(*args)
  lower_s = time.perf_counter() - start
  start = time.perf_counter()
  program = lowered.compile()
  compile_s = time.perf_counter() - start
  start = time.perf_counter()
  out = jax.block_until_ready(program(*args))
  return {'lower_s': round(lower_s, 2), 'compile_s': round(compile_s, 2),
          'run_s': round(time.perf_counter() - start, 3)}, out


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--config', default='default')
  parser.add_argument('--backend', default='mjx')
  parser.add_argument('--batch', type=int, default=8)
  args = parser.parse_args(argv)
  config = resolve(args.config, [f'scene.backend={args.backend}'])
  task = Task.build(config, methods.get(config.network.method).views)
  env = task.env
  keys = jax.random.split(jax.random.PRNGKey(0), args.batch)
  row = {'benchmark': 'mjx_compile', 'config': args.config, 'backend': args.backend,
         'batch': args.batch, 'jax': jax.__version__, 'device': str(jax.devices()[0])}
  row['reset'], states = compiled(jax.vmap(env.reset), keys)
  row['observe'], obs = compiled(task.observe, states)
  q = jax.numpy.zeros((args.batch, 2, config.env.num_rotations) + obs.depth.shape[-2:])
  pick = agent.greedy_actions(q, jax.numpy.ones(args.batch, bool),
                              methods.get(config.network.method))
  action = task.to_world(pick, obs.depth)
  row['step'], _ = compiled(jax.vmap(env.step), states, action)
  row['reset_and_step'], _ = compiled(
      lambda k, s, a: (jax.vmap(env.reset)(k), jax.vmap(env.step)(s, a)), keys, states, action)
  drops = jax.jit(jax.vmap(env.drop))(keys)
  row['step_and_settle'], _ = compiled(
      jax.vmap(env.step_and_settle, in_axes=(0, 0, 0, None)), states, action, drops, True)
  print(json.dumps(row, indent=1))
  return 0


if __name__ == '__main__':
  raise SystemExit(main())
