"""What finished evaluation runs cost the batch they wait in, per suite.

`mvcoba-eval` steps every (case, run) pair of a suite in lockstep, so finished runs keep
stepping until the batch moves the runs still going to a smaller one (`runner.evaluate`);
meanwhile they step on an emptied table (`Tabletop.emptied`). This times one lockstep action (the
heuristic's primitive, then both cameras) of a batch holding every case of a suite once, settled
as the evaluation starts them, against the same batch emptied, on the native backend; reads
from an evaluation's results.json how many of the lockstep steps were taken by runs that had
already finished; and with --checkpoint, times the whole evaluation of the suite (--runs per case)
in one batch throughout against the same with the runs moving to smaller batches, and says
whether their counters agree. Prints one JSON object.

  python benchmarks/finished_runs.py [--suite random ordered occluded] [--repeats 3]
                                     [--results docs/results/six-methods/results.json]
                                     [--checkpoint runs/train --runs 5]
"""
from __future__ import annotations

import argparse
import json
import pathlib
import statistics
import sys
import time

import jax
from physics import settings  # noqa: E402

from mvcoba_jax import runtime  # noqa: E402
from mvcoba_jax.evaluation import runner  # noqa: E402
from mvcoba_jax.config import resolve  # noqa: E402
from mvcoba_jax.learner.task import Task  # noqa: E402
from mvcoba_jax.evaluation.protocols import FROZEN  # noqa: E402
from mvcoba_jax.evaluation.sources import trained  # noqa: E402
from mvcoba_jax.sim.scenarios import case_to_layout, read_case, stack_layouts  # noqa: E402
from mvcoba_jax.suites import suite_files  # noqa: E402
from mvcoba_jax.suites import cases as suite_cases  # noqa: E402


def step_cost(suite: str, repeats: int) -> dict:
  cases = [read_case(f) for f in suite_files([suite])[suite]]
  config = resolve(None)
  task = Task.build(suite_cases.suite_config(config, suite_cases.pool_for(cases)), (0, 1))
  env = task.env
  n = len(cases)
  layouts = stack_layouts([case_to_layout(c, env) for c in cases])
  states, _ = jax.jit(lambda l, k: suite_cases.start(env, l, k))(
      layouts, jax.random.split(jax.random.PRNGKey(0), n))
  policy = runner.heuristic_actor(config.env.num_rotations)

  @jax.jit
  def action(states, key):
    begun = task.begin(states)
    chosen = policy.choose(begun.obs, begun.changed, jax.random.split(key, n), None)
    return task.step(begun, chosen)

  emptied = jax.jit(jax.vmap(env.emptied))(states)
  times = {'full': [], 'emptied': []}
  jax.block_until_ready(action(states, jax.random.PRNGKey(0)))  # compile
  for r in range(repeats):  # interleaved, so drifting load hits both alike
    for name, batch in (('full', states), ('emptied', emptied)):
      t = time.perf_counter()
      jax.block_until_ready(action(batch, jax.random.PRNGKey(r)))
      times[name].append(time.perf_counter() - t)
  full, empty = statistics.median(times['full']), statistics.median(times['emptied'])
  return {'suite': suite, 'batch': n, 'objects_in_play': int(states.in_play.sum()),
          'full_action_s': full, 'emptied_action_s': empty, 'emptied_over_full': empty / full}


def whole_suite(suite: str, checkpoint: str, runs: int) -> dict:
  """Wall time of a suite's evaluation kept in one batch, and moving to smaller batches."""
  cases = [read_case(f) for f in suite_files([suite])[suite]]
  source = trained(checkpoint)
  config = suite_cases.suite_config(source.config, suite_cases.pool_for(cases))
  task = Task.build(config, source.views)
  policy = source.actor(config, FROZEN)
  layouts = stack_layouts([case_to_layout(c, task.env) for c in cases for _ in range(runs)])
  keys = jax.random.split(jax.random.PRNGKey(0), len(cases) * runs)
  n = len(cases) * runs
  row = {'suite': suite, 'checkpoint': checkpoint, 'runs': n}
  logs = {}
  for name, smallest in (('one_batch', n), ('smaller_batches', 8)):
    t = time.perf_counter()
    logs[name] = runner.run_logs(runner.evaluate(task, policy, layouts, keys, 60,
                                                 smallest=smallest), task)
    row[f'{name}_s'] = time.perf_counter() - t  # compiles included: each batch size compiles
  row['smaller_over_one'] = row['smaller_batches_s'] / row['one_batch_s']
  row['runs_that_differ'] = sum(a != b for a, b in zip(logs['one_batch'], logs['smaller_batches']))
  return row


def idle_share(results: str) -> dict:
  """Per suite, the share of lockstep steps taken by runs that had finished (each policy's
  batch steps until its longest run ends)."""
  report = json.loads(pathlib.Path(results).read_text())
  share = {}
  for suite, rows in report.items():
    used = steps = 0
    for row in rows.values():
      actions = [log['actions'] for logs in row['runs'].values() for log in logs]
      used, steps = used + sum(actions), steps + len(actions) * max(actions)
    share[suite] = 1.0 - used / steps
  return share


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--suite', nargs='+', default=['dev-random', 'dev-ordered', 'dev-occluded'])
  parser.add_argument('--repeats', type=int, default=3)
  parser.add_argument('--results', default='docs/results/six-methods/results.json',
                      help="an evaluation's results.json, for the share of finished runs' steps")
  parser.add_argument('--checkpoint', help='a policy to time whole evaluations with')
  parser.add_argument('--runs', type=int, default=5, help='runs per case of those evaluations')
  args = parser.parse_args()
  runtime.setup()
  whole = [whole_suite(s, args.checkpoint, args.runs) for s in args.suite] if args.checkpoint else []
  rows = [step_cost(s, args.repeats) for s in args.suite]
  idle = idle_share(args.results)
  for row in rows:
    share = idle.get(row['suite'])
    row['finished_share_of_steps'] = share
    if share is not None:  # the evaluation's time with finished runs emptied, over kept as they were
      row['expected_eval_time_ratio'] = 1.0 - share * (1.0 - row['emptied_over_full'])
  json.dump({'benchmark': 'finished_runs', 'settings': settings() | {
      'repeats': args.repeats, 'results': args.results, 'policy': 'heuristic'},
      'results': rows, 'whole_suites': whole}, sys.stdout, indent=1)
  print()


if __name__ == '__main__':
  main()
