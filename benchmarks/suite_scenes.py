"""Physics cost of each evaluation suite's scene, on the native and the MJX backend.

`mvcoba-eval` builds one scene per suite: the object-slot pool that holds every case, with contact
limits that grow with it (`suite_cases.suite_config`). This times one scripted grasp (the full
primitive) from each suite's largest case in that scene, on both backends from the same settled
start state, and prints one JSON object. `--batch N` runs N copies of the case
in lockstep, as `mvcoba-eval` does.

  python benchmarks/suite_scenes.py [--suite ordered random] [--repeats 1] [--batch 1]
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys

import jax  # noqa: E402
from physics import backend_row, grasp_actions, settings  # noqa: E402

from mvcoba_jax.config import resolve  # noqa: E402
from mvcoba_jax.sim.scenarios import case_to_layout, read_case, stack_layouts  # noqa: E402
from mvcoba_jax.sim.tabletop import Tabletop  # noqa: E402
from mvcoba_jax.suites import SUITES, suite_files  # noqa: E402
from mvcoba_jax.suites import cases as suite_cases  # noqa: E402


def bench(suite: str, repeats: int, batch: int) -> dict:
  files = suite_files([suite])[suite]
  cases = [read_case(f) for f in files]
  config = suite_cases.suite_config(resolve(None), suite_cases.pool_for(cases))
  env_on = lambda backend: Tabletop(dataclasses.replace(
      config, scene=dataclasses.replace(config.scene, backend=backend)).tabletop)
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
  parser.add_argument('--suite', nargs='+', default=['dev-ordered', 'dev-random'],
                      choices=SUITES)
  parser.add_argument('--repeats', type=int, default=1)
  parser.add_argument('--batch', type=int, default=1)
  args = parser.parse_args()
  rows = []
  for suite in args.suite:
    rows.append(bench(suite, args.repeats, args.batch))
    print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
  print(json.dumps({
      'benchmark': 'suite_scenes',
      'settings': {**settings(), 'batch': args.batch,
                   'repeats': args.repeats,
                   'primitive': "grasp at the largest case's first object, full script"},
      'results': rows,
  }, indent=1))


if __name__ == '__main__':
  main()
