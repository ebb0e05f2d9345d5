"""Rendering + heightmap throughput of both backends' ray casters, two cameras per environment.

Prints one JSON object: for each preset (the CPU default: 160 x 160 cameras -> 112 x 112 grid;
the paper's: 320 x 320 -> 224 x 224) and batch size, the compile time, the time per batch and
per environment of `vmap(observe)` and rays cast per second, with native MuJoCo's `mj_ray` on
CPU threads and (at the `--mjx-batch` sizes) with `mjx.ray`, and their ratio in the same run.
Scenes are random drops of the preset, placed without settling (rendering cost does not depend
on it).

  python benchmarks/perception.py [--batch 1 8 32] [--mjx-batch 8] [--presets default paper]
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time

import jax  # noqa: E402
import numpy as np  # noqa: E402

from mvcoba_jax import perception  # noqa: E402
from mvcoba_jax.config import resolve  # noqa: E402
from mvcoba_jax.learner.task import Task  # noqa: E402
from mvcoba_jax.sim.native import default_threads  # noqa: E402
from mvcoba_jax.sim.tabletop import Tabletop  # noqa: E402


def timed(fn, *args):
  t = time.perf_counter()
  out = jax.block_until_ready(fn(*args))
  return out, time.perf_counter() - t


def measure(config, batch: int, repeats: int) -> dict:
  task = Task.build(config, (0, 1))
  env = task.env
  keys = jax.random.split(jax.random.PRNGKey(0), batch)
  states = jax.jit(jax.vmap(lambda k: env.place(env.sample_layout(k))))(keys)
  observe = jax.jit(task.observe)
  obs, first = timed(observe, states)
  wall = float(np.median([timed(observe, states)[1] for _ in range(repeats)]))
  rays = batch * sum(c.width * c.height for c in config.scene.cameras)
  return {'compile_s': first - wall, 'batch_wall_s': wall, 'per_env_s': wall / batch,
          'rays_per_s': rays / wall,
          'seen_fraction_per_view': np.asarray(obs.seen).mean(axis=(0, 2, 3)).round(3).tolist()}


def bench(preset: str, batch: int, mjx: bool, repeats: int) -> dict:
  config = resolve(preset)
  on = lambda backend: dataclasses.replace(
      config, scene=dataclasses.replace(config.scene, backend=backend))
  row = {'preset': preset, 'batch': batch,
         'grid': perception.grid_size(config.perception, config.scene),
         'camera_pixels': [[c.width, c.height] for c in config.scene.cameras],
         'geoms': int(Tabletop(config.tabletop).scene.mj_model.ngeom),
         'native': measure(on('native'), batch, repeats)}
  if mjx:
    row['mjx'] = measure(on('mjx'), batch, repeats)
    row['native_over_mjx'] = row['mjx']['batch_wall_s'] / row['native']['batch_wall_s']
  return row


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--batch', type=int, nargs='+', default=[1, 8, 32])
  parser.add_argument('--mjx-batch', type=int, nargs='*', default=[8],
                      help='batch sizes at which mjx.ray is measured too (none: native only)')
  parser.add_argument('--presets', nargs='+', default=['default', 'paper'])
  parser.add_argument('--repeats', type=int, default=2)
  args = parser.parse_args()
  rows = []
  for preset in args.presets:
    for b in args.batch:
      rows.append(bench(preset, b, b in args.mjx_batch, args.repeats))
      print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
  for r in rows:
    one = [o for o in rows if o['preset'] == r['preset'] and o['batch'] == min(args.batch)][0]
    r['native_per_env_speedup_vs_smallest_batch'] = (one['native']['per_env_s']
                                                     / r['native']['per_env_s'])
  print(json.dumps({'benchmark': 'perception',
                    'settings': {'native': 'mujoco.batch.Batch.ray (mj_ray per pixel) on '
                                           f'{default_threads()} threads',
                                 'mjx': 'mjx.ray vmapped over pixels', 'jax': jax.__version__,
                                 'device': str(jax.devices()[0]), 'cpu_count': os.cpu_count()},
                    'results': rows}, indent=1))


if __name__ == '__main__':
  main()
