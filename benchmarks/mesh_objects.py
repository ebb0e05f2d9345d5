"""Mesh objects against blocks: physics throughput and decomposition time.

Prints one JSON object: primitives/s of `jit(vmap(env.step))` (a grasp at one object of a heap of
10 dropped by `reset`) on scenes of 10 blocks, 10 of the procedural training objects and 10 of the
held-out everyday objects, on the native backend and (with --mjx) MJX's JAX implementation, each
with its ratio to the blocks measured in the same run; and the seconds CoACD takes to split a
non-convex file the first time and to read its parts from the cache the second.

  python benchmarks/mesh_objects.py [--batch 8] [--repeats 3] [--mjx]
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import pathlib
import platform
import tempfile
import time

import jax
import numpy as np
import trimesh

from mvcoba_jax import runtime
from mvcoba_jax.config import resolve
from mvcoba_jax.sim import meshes, procedural
from mvcoba_jax.sim.primitives import GRASP, Action
from mvcoba_jax.sim.tabletop import Tabletop

SETS = {
    'blocks': None,
    'procedural': [str(p) for p in procedural.training_objects()[:10]],
    'everyday': sorted(str(p) for p in (procedural.OBJECTS / 'everyday').iterdir()
                       if p.is_dir())[:10],
}


def make_env(objects, backend: str) -> Tabletop:
  base = resolve('default')
  pool = base.scene.pool if objects is None else tuple((o, 1) for o in objects)
  scene = dataclasses.replace(base.scene, pool=pool, backend=backend,
                              max_geom_pairs=96, max_contact_points=384)
  env = dataclasses.replace(base.env, num_objects=10)
  return Tabletop(dataclasses.replace(base, scene=scene, env=env).tabletop)


def throughput(env: Tabletop, batch: int, repeats: int) -> dict:
  states = jax.jit(jax.vmap(env.reset))(jax.random.split(jax.random.PRNGKey(0), batch))
  xy = np.asarray(jax.vmap(env.object_positions)(states))[:, :, :2]
  slot = np.argmax(np.asarray(states.in_play), axis=1)
  target = xy[np.arange(batch), slot]
  action = Action(primitive=np.full(batch, GRASP, np.int32), rotation=np.zeros(batch, np.int32),
                  x=target[:, 0].astype(np.float32), y=target[:, 1].astype(np.float32),
                  z=np.full(batch, 0.03, np.float32))
  step = jax.jit(jax.vmap(env.step))
  began = time.perf_counter()
  jax.block_until_ready(step(states, action))
  first = time.perf_counter() - began
  times = []
  for _ in range(repeats):
    began = time.perf_counter()
    jax.block_until_ready(step(states, action))
    times.append(time.perf_counter() - began)
  return {'first_call_s': round(first, 2), 'primitive_s': round(float(np.median(times)), 3),
          'primitives_per_s': round(batch / float(np.median(times)), 2)}


def decomposition() -> dict:
  """CoACD on an L of two boxes, in a cache of its own: first (split) and second (read)."""
  with tempfile.TemporaryDirectory() as folder:
    os.environ['MVCOBA_JAX_CACHE'] = str(pathlib.Path(folder) / 'jax')
    leg = trimesh.creation.box((0.08, 0.02, 0.02))
    leg.apply_translation((0.04, 0.01, 0.0))
    other = trimesh.creation.box((0.02, 0.06, 0.02))
    other.apply_translation((0.01, 0.05, 0.0))
    path = pathlib.Path(folder) / 'ell.obj'
    trimesh.util.concatenate([leg, other]).export(path)
    out = {}
    for run in ('first_s', 'cached_s'):
      meshes.parts.cache_clear()
      began = time.perf_counter()
      parts = meshes.parts(str(path))
      out[run] = round(time.perf_counter() - began, 3)
    out['parts'] = len(parts)
  return out


def main():
  parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
  parser.add_argument('--batch', type=int, default=8)
  parser.add_argument('--repeats', type=int, default=3)
  parser.add_argument('--mjx', action='store_true', help='also MJX (compiles for minutes)')
  args = parser.parse_args()
  jax_cache = os.environ.get('MVCOBA_JAX_CACHE')
  runtime.setup()
  result = {'settings': {'batch': args.batch, 'repeats': args.repeats, 'objects': 10,
                         'primitive': 'grasp', 'cpus': os.cpu_count(),
                         'machine': platform.machine()}}
  for backend in ('native', 'mjx') if args.mjx else ('native',):
    rows = {name: throughput(make_env(objects, backend), args.batch, args.repeats)
            for name, objects in SETS.items()}
    for row in rows.values():
      row['vs_blocks'] = round(row['primitives_per_s'] / rows['blocks']['primitives_per_s'], 3)
    result[backend] = rows
  result['decomposition'] = decomposition()
  result['settings']['load_average_1min_at_end'] = round(os.getloadavg()[0], 2)
  if jax_cache:
    os.environ['MVCOBA_JAX_CACHE'] = jax_cache
  print(json.dumps(result, indent=1))


if __name__ == '__main__':
  main()
