"""The acting forward alone (B states x all rotations, the default preset's network), for each way
of turning and padding, trunk width and float32 and bfloat16, in one run, with the shipped
policy's trained parameters (pretrained/mvcoba: every variant of its width has the same
parameters, only the turn differs; a narrower trunk has its own initial ones); whether the
action bfloat16 picks is float32's, or one whose float32 Q value is within `--tolerance` of the
best.

Prints one JSON object: per variant the compile and median wall time of the jitted forward, its
time over the first variant's, and for bfloat16 the share of states whose greedy action (argmax
over both primitives' maps) is float32's, the share whose float32 Q is within the tolerance of
float32's best, and the largest shortfall (float32's best minus float32's Q of bfloat16's pick).

  python benchmarks/acting_forward.py [--batch 8] [--repeats 5] [--tolerance 0.01]
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
from flax import nnx  # noqa: E402
from physics import timed  # noqa: E402

from mvcoba_jax import policy  # noqa: E402
from mvcoba_jax.learner import networks  # noqa: E402
from mvcoba_jax.perception import grid_size  # noqa: E402

POLICY = ROOT / 'pretrained' / 'mvcoba'

VARIANTS = [  # (name, network overrides, dtype)
    ('turned_heightmaps', {}, jnp.float32),
    ('turned_heightmaps_bf16', {}, jnp.bfloat16),
    ('padded_heightmaps', {'pad_to_diagonal': True}, jnp.float32),
    ('turned_stems', {'shared_stages': 1}, jnp.float32),
    ('turned_first_block', {'shared_stages': 2}, jnp.float32),
    ('turned_first_block_bf16', {'shared_stages': 2}, jnp.bfloat16),
    ('padded_first_block', {'shared_stages': 2, 'pad_to_diagonal': True}, jnp.float32),
    ('trunk_16_32_32', {'features': (16, 32, 32)}, jnp.float32),
    ('trunk_16_32_32_turned_stems', {'features': (16, 32, 32), 'shared_stages': 1}, jnp.float32),
]


def states(batch: int, views: int, side: int):
  """Random heightmaps shaped like a scene's: colour 0..1, depth 0..0.1 m, mostly low."""
  kc, kd = jax.random.split(jax.random.key(0))
  color = jax.random.uniform(kc, (batch, views, side, side, 3))
  depth = 0.1 * jax.random.uniform(kd, (batch, views, side, side)) ** 4
  return color, depth


def shortfall(q_float32, q_other):
  """(B, 2, K, R, R) twice -> (B,) whether the greedy picks agree, and float32's best Q minus
  float32's Q of the other's pick."""
  want = q_float32.reshape(q_float32.shape[0], -1)
  picked = jnp.argmax(q_other.reshape(want.shape).astype(jnp.float32), axis=1)
  same = picked == jnp.argmax(want, axis=1)
  return same, jnp.max(want, axis=1) - jnp.take_along_axis(want, picked[:, None], 1)[:, 0]


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--batch', type=int, default=8)
  parser.add_argument('--repeats', type=int, default=5)
  parser.add_argument('--tolerance', type=float, default=0.01)
  args = parser.parse_args()
  config, model, _ = policy.load(POLICY)
  _, trained = nnx.split(model)
  side, k = grid_size(config.perception, config.scene), config.env.num_rotations
  color, depth = states(args.batch, len(config.scene.cameras), side)
  rows, reference = [], {}
  for name, overrides, dtype in VARIANTS:
    network = dataclasses.replace(config.network, **overrides)
    graphdef, own = nnx.split(networks.build_network(network, k, nnx.Rngs(0)))
    # another width has other shapes: its own initial parameters (the time does not depend on them)
    params = trained if 'features' not in overrides else own
    cast = lambda tree: jax.tree.map(lambda x: x.astype(dtype), tree)
    forward = jax.jit(lambda p, c, d: nnx.merge(graphdef, cast(p))(cast(c), cast(d)))
    q, first, wall = timed(forward, params, color, depth, repeats=args.repeats)
    row = {'variant': name, 'network': overrides, 'dtype': jnp.dtype(dtype).name,
           'compile_s': first - wall, 'wall_s': wall}
    key = json.dumps(overrides, sort_keys=True)
    if dtype == jnp.float32:
      reference[key] = q
    elif key in reference:
      same, short = shortfall(reference[key], q)
      row['same_action_share'] = float(same.mean())
      row['within_tolerance_share'] = float((short <= args.tolerance).mean())
      row['max_shortfall'] = float(short.max())
    rows.append(row)
    print(json.dumps(row), file=sys.stderr, flush=True)
  for row in rows:
    row['over_first'] = row['wall_s'] / rows[0]['wall_s']
  print(json.dumps({'benchmark': 'acting_forward', 'policy': str(POLICY.relative_to(ROOT)),
                    'batch': args.batch, 'rotations': k,
                    'grid': side, 'tolerance': args.tolerance, 'jax': jax.__version__,
                    'device': str(jax.devices()[0]), 'cpu_count': os.cpu_count(),
                    'results': rows}, indent=1))


if __name__ == '__main__':
  main()
