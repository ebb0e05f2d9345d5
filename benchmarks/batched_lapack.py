"""Does jaxlib's batched LAPACK path hang on this machine? MJX-shaped calls, trial by trial.

The workload is what a vmapped MJX step asks of LAPACK: in one jitted program, two independent
batched Cholesky factorizations, each followed by a solve (the mass matrix and the Newton
solver's Hessian), over B environments of n dof. Each trial runs it in a fresh process for
`--seconds` and counts as hung when it has not finished `--grace` seconds later. jaxlib 0.10
deadlocked here on 2 cores (docs/results/archive/history.md); from 0.11.1 it should not. BLAS is
serial, as `runtime.setup()` leaves it. Prints one JSON object.

  python benchmarks/batched_lapack.py [--batch 8] [--dof 288] [--trials 6] [--seconds 15]
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time


def trial(batch: int, dof: int, seconds: float) -> None:
  """One trial, in this process: prints the number of calls made and the seconds taken."""
  import jax
  import jax.numpy as jnp

  from mvcoba_jax import runtime
  runtime.setup()

  def factor_and_solve(a, b):
    return jax.scipy.linalg.cho_solve(jax.scipy.linalg.cho_factor(a), b)

  @jax.jit
  def two_independent(a, b, rhs):
    return (jax.vmap(factor_and_solve)(a, rhs).sum() + jax.vmap(factor_and_solve)(b, rhs).sum())

  m = jax.random.normal(jax.random.PRNGKey(0), (batch, dof, dof))
  spd = m @ jnp.swapaxes(m, 1, 2) + dof * jnp.eye(dof)
  rhs = jnp.ones((batch, dof))
  two_independent(spd, 2 * spd, rhs).block_until_ready()
  calls, start = 0, time.perf_counter()
  while time.perf_counter() - start < seconds:
    two_independent(spd, 2 * spd, rhs).block_until_ready()
    calls += 1
  print(calls, time.perf_counter() - start)


def run(args) -> dict:
  hung, rates = 0, []
  for _ in range(args.trials):
    cmd = [sys.executable, __file__, '--trial', '--batch', str(args.batch),
           '--dof', str(args.dof), '--seconds', str(args.seconds)]
    try:
      out = subprocess.run(cmd, capture_output=True, text=True, check=True,
                           timeout=args.seconds + args.grace).stdout.split()
      rates.append(int(out[-2]) / float(out[-1]))
    except subprocess.TimeoutExpired:
      hung += 1
    print(f'{len(rates)} finished, {hung} hung', file=sys.stderr, flush=True)
  return {'trials': args.trials, 'hung': hung,
          'calls_per_s': round(sum(rates) / len(rates), 1) if rates else None}


def main():
  parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
  parser.add_argument('--batch', type=int, default=8)
  parser.add_argument('--dof', type=int, default=288, help='288: the random suite\'s scene')
  parser.add_argument('--trials', type=int, default=6)
  parser.add_argument('--seconds', type=float, default=15.0)
  parser.add_argument('--grace', type=float, default=30.0, help='past --seconds: hung')
  parser.add_argument('--trial', action='store_true', help=argparse.SUPPRESS)
  args = parser.parse_args()
  if args.trial:
    return trial(args.batch, args.dof, args.seconds)
  import jaxlib
  print(json.dumps({
      'benchmark': 'batched_lapack',
      'settings': {'batch': args.batch, 'dof': args.dof, 'seconds_per_trial': args.seconds,
                   'grace_s': args.grace, 'cpus': os.cpu_count(), 'machine': platform.machine(),
                   'jaxlib': jaxlib.__version__},
      'results': {'batched': run(args)},
  }, indent=1))


if __name__ == '__main__':
  main()
