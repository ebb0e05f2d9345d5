"""How many objects of each case stay in the workspace while the case settles.

A run is scored against the objects in play after `reset_from_case` settles the case, so objects
that slide or bounce out while a pile settles never count. This settles every case of a suite
with `--keys` placement jitters, exactly as `mvcoba-eval` starts its runs (same scene, same jitter),
and prints one JSON object: per case, the objects its file lists, those still in play after
each key, and those of them within `--edge` of the workspace's border (a run loses objects
there to any push or nudge). `--suite` takes a suite's name or a folder of case files (e.g. a
candidate written by suites/generate.py's `random_case`). Settling uses the default preset.

  python benchmarks/suite_settling.py [--suite random] [--keys 2] [--edge 0.03]
"""
from __future__ import annotations

import argparse
import json
import pathlib
import time

import jax  # noqa: E402
import numpy as np  # noqa: E402
from physics import settings  # noqa: E402

from mvcoba_jax.config import resolve  # noqa: E402
from mvcoba_jax.sim.scenarios import read_case  # noqa: E402
from mvcoba_jax.suites import suite_files  # noqa: E402
from mvcoba_jax.suites import cases as suite_cases  # noqa: E402


def settle(files: list[pathlib.Path], keys: int, edge: float) -> list[dict]:
  cases = [read_case(f) for f in files]
  env, states = suite_cases.settled_starts(cases, resolve(None), keys)
  xy = np.abs(np.asarray(jax.vmap(env.object_positions)(states))[..., :2]).max(axis=-1)
  play = np.asarray(states.in_play)
  near = play & (xy > env.config.scene.workspace_half - edge)
  in_play, near = (a.sum(axis=1).reshape(len(cases), keys) for a in (play, near))
  return [{'case': c.name, 'listed': len(c.objects), 'in_play': in_play[i].tolist(),
           'near_edge': near[i].tolist(),
           'left_workspace_max': int(len(c.objects) - in_play[i].min())}
          for i, c in enumerate(cases)]


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--suite', default='dev-random', help='a suite name or a folder of cases')
  parser.add_argument('--keys', type=int, default=2, help='placement jitters per case')
  parser.add_argument('--edge', type=float, default=0.03, help='m from the border: near it')
  args = parser.parse_args()
  files = suite_files([args.suite])[args.suite]
  t0 = time.perf_counter()
  rows = settle(files, args.keys, args.edge)
  listed = sum(r['listed'] for r in rows) * args.keys
  kept = sum(sum(r['in_play']) for r in rows)
  print(json.dumps({
      'benchmark': 'suite_settling',
      'settings': {**settings(), 'suite': args.suite, 'keys': args.keys, 'edge': args.edge,
                   'settle_steps': resolve(None).env.settle_steps},
      'wall_s': time.perf_counter() - t0,
      'objects_kept_fraction': kept / listed,
      'near_edge_total': sum(sum(r['near_edge']) for r in rows),
      'results': rows,
  }, indent=1))


if __name__ == '__main__':
  main()
