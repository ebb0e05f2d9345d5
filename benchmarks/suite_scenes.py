"""Physics cost of each evaluation suite's scene, with MJX and with native MuJoCo.

`eval.py` builds one scene per suite: the object-slot pool that holds every case, with contact
limits that grow with it (`eval.suite_config`). This times one scripted grasp (the full
primitive) from each suite's largest case in that scene, with MJX and with native MuJoCo on the
same start state and controls, and prints one JSON object. `--batch N` runs N copies of the case
in lockstep, as `eval.py` does; `--lapack batched` times jaxlib's batched LAPACK calls instead
of envs/cpu_linalg.py's loop over matrices (which a batch of 1 does not use).

  python benchmarks/suite_scenes.py [--suite ordered random] [--repeats 1] [--batch 1]
      [--lapack loop|batched]
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
from envs import cpu_linalg  # noqa: E402
from envs.scenarios import case_to_layout, read_case, stack_layouts  # noqa: E402
from envs.tabletop import Tabletop  # noqa: E402
from mvcoba_jax.config import resolve  # noqa: E402
from physics import grasp_actions, native, settings, timed  # noqa: E402


def bench(suite: str, repeats: int, batch: int) -> dict:
  files = evaluation_cli.suite_files([suite], evaluation_cli.VPG_CASES)[suite]
  cases = [read_case(f) for f in files]
  env = Tabletop(evaluation_cli.suite_config(resolve(None), evaluation_cli.pool_for(cases)))
  largest = max(cases, key=lambda c: len(c.objects))
  layouts = stack_layouts([case_to_layout(largest, env)] * batch)
  states = jax.jit(jax.vmap(env.reset_from_case))(layouts,
                                                   jax.random.split(jax.random.PRNGKey(0), batch))
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
      'env_steps_per_s': batch * env.script.length / wall,
      'grasp_success': bool(np.asarray(info.grasp_success)[0]),
  }
  row.update(native(env, states, actions, batch))
  row['native_loop_over_mjx'] = row['mj_step_loop_env_steps_per_s'] / row['env_steps_per_s']
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
  for r in rows:
    r['grasp_wall_over_first_suite'] = r['grasp_wall_s'] / rows[0]['grasp_wall_s']
  print(json.dumps({
      'benchmark': 'suite_scenes',
      'settings': {**settings(), 'batch': args.batch, 'lapack': args.lapack,
                   'repeats': args.repeats,
                   'primitive': "grasp at the largest case's first object, full script"},
      'results': rows,
  }, indent=1))


if __name__ == '__main__':
  main()
