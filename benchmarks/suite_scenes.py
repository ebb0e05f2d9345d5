"""Physics cost of each evaluation suite's scene, with MJX and with native MuJoCo.

`eval.py` builds one scene per suite: the object-slot pool that holds every case, with contact
limits that grow with it (`eval.suite_config`). This times one scripted grasp (B=1, the full
primitive) from each suite's largest case in that scene, with MJX and with native MuJoCo on the
same start state and controls, and prints one JSON object.

  python benchmarks/suite_scenes.py [--suite ordered random] [--repeats 1]
"""
from __future__ import annotations

import argparse
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / 'benchmarks'))

import jax  # noqa: E402
import numpy as np  # noqa: E402

import eval as evaluation_cli  # noqa: E402
from envs.scenarios import case_to_layout, read_case, stack_layouts  # noqa: E402
from envs.tabletop import Tabletop  # noqa: E402
from mvcoba_jax.config import resolve  # noqa: E402
from physics import grasp_actions, native, settings, timed  # noqa: E402


def bench(suite: str, repeats: int) -> dict:
  files = evaluation_cli.suite_files([suite], ROOT.parent / 'shared' / 'vpg-test-cases')[suite]
  cases = [read_case(f) for f in files]
  env = Tabletop(evaluation_cli.suite_config(resolve(None), evaluation_cli.pool_for(cases)))
  largest = max(cases, key=lambda c: len(c.objects))
  layouts = stack_layouts([case_to_layout(largest, env)])
  states = jax.jit(jax.vmap(env.reset_from_case))(layouts, jax.random.split(jax.random.PRNGKey(0), 1))
  step = jax.jit(jax.vmap(env.step))
  actions = grasp_actions(env, states)
  (_, info), first = timed(step, states, actions)
  wall = float(np.median([timed(step, states, actions)[1] for _ in range(repeats)]))
  scene = env.config.scene
  row = {
      'suite': suite, 'case': largest.name, 'objects_in_play': len(largest.objects),
      'slots': scene.num_slots, 'max_geom_pairs': scene.max_geom_pairs,
      'max_contact_points': scene.max_contact_points, 'physics_steps': env.script.length,
      'step_compile_s': first - wall, 'grasp_wall_s': wall,
      'env_steps_per_s': env.script.length / wall,
      'grasp_success': bool(np.asarray(info.grasp_success)[0]),
  }
  row.update(native(env, states, actions, 1))
  row['native_loop_over_mjx'] = row['mj_step_loop_env_steps_per_s'] / row['env_steps_per_s']
  return row


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--suite', nargs='+', default=['ordered', 'random'],
                      choices=evaluation_cli.SUITES)
  parser.add_argument('--repeats', type=int, default=1)
  args = parser.parse_args()
  rows = []
  for suite in args.suite:
    rows.append(bench(suite, args.repeats))
    print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
  for r in rows:
    r['grasp_wall_over_first_suite'] = r['grasp_wall_s'] / rows[0]['grasp_wall_s']
  print(json.dumps({
      'benchmark': 'suite_scenes',
      'settings': {**settings(), 'batch': 1, 'repeats': args.repeats,
                   'primitive': "grasp at the largest case's first object, full script"},
      'results': rows,
  }, indent=1))


if __name__ == '__main__':
  main()
