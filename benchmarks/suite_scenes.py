"""Physics cost of each evaluation suite's scene, on the native and the MJX backend.

`eval.py` builds one scene per suite: the object-slot pool that holds every case, with contact
limits that grow with it (`eval.suite_config`). This times one scripted grasp (the full
primitive) from each suite's largest case in that scene, on both backends from the same settled
start state, and prints one JSON object. `--batch N` runs N copies of the case
in lockstep, as `eval.py` does; `--lapack batched` times jaxlib's batched LAPACK calls instead
of envs/cpu_linalg.py's loop over matrices (which a batch of 1 does not use).

  python benchmarks/suite_scenes.py [--suite ordered random] [--repeats 1] [--batch 1]
      [--lapack loop|batched]
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / 'benchmarks'))

import jax  # noqa: E402

import eval as evaluation_cli  # noqa: E402
from envs import cpu_linalg  # noqa: E402
from envs.scenarios import case_to_layout, read_case, stack_layouts  # noqa: E402
from envs.tabletop import Tabletop  # noqa: E402
from mvcoba_jax.config import resolve  # noqa: E402
from physics import backend_row, grasp_actions, settings  # noqa: E402


def bench(suite: str, repeats: int, batch: int) -> dict:
  files = evaluation_cli.suite_files([suite], evaluation_cli.VPG_CASES)[suite]
  cases = [read_case(f) for f in files]
  config = evaluation_cli.suite_config(resolve(None), evaluation_cli.pool_for(cases))
  env_on = lambda backend: Tabletop(dataclasses.replace(
      config, scene=dataclasses.replace(config.scene, backend=backend)))
  native = env_on('native')
  largest = max(cases, key=lambda c: len(c.objects))
  layouts = stack_layouts([case_to_layout(largest, native)] * batch)
  states = jax.jit(jax.vmap(native.reset_from_case))(
      layouts, jax.random.split(jax.random.PRNGKey(0), batch))
  actions = grasp_actions(native, states)
  scene = config.scene
  row = {
      'suite': suite, 'case': largest.name, 'objects_in_play': len(largest.objects),
      'slots': scene.num_slots, 'max_geom_pairs': scene.max_geom_pairs,
      'max_contact_points': scene.max_contact_points, 'physics_steps': native.script.length,
      'native': backend_row(native, states, actions, repeats),
      'mjx': backend_row(env_on('mjx'), states, actions, repeats),
  }
  row['native_over_mjx'] = row['native']['env_steps_per_s'] / row['mjx']['env_steps_per_s']
  return row


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--suite', nargs='+', default=['ordered', 'random'],
                      choices=evaluation_cli.SUITES)
  parser.add_argument('--repeats', type=int, default=1)
  parser.add_argument('--batch', type=int, default=1)
  parser.add_argument('--lapack', choices=('loop', 'batched'), default='loop')
  args = parser.parse_args()
  if args.lapack == 'batched':
    cpu_linalg.use_jaxlib_batched_calls()
  rows = []
  for suite in args.suite:
    rows.append(bench(suite, args.repeats, args.batch))
    print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
  print(json.dumps({
      'benchmark': 'suite_scenes',
      'settings': {**settings(), 'batch': args.batch, 'lapack': args.lapack,
                   'repeats': args.repeats,
                   'primitive': "grasp at the largest case's first object, full script"},
      'results': rows,
  }, indent=1))


if __name__ == '__main__':
  main()
