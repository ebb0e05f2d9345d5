"""What the online test protocol costs against the frozen one (`mvcoba-eval --online`).

For each suite, evaluates one policy frozen and online (`runner.Online`: every run
takes one SGD step after each of its actions) with --runs per case and the 60-action cap, each
twice in turn: the first call compiles (every batch size the runs move through), the second is
timed warm. Online runs take other actions than frozen ones, so besides each suite's wall time
it reports the seconds per action the runs executed. Prints one JSON object.

  python benchmarks/online_eval.py --checkpoint pretrained/mvcoba [--suite ordered occluded]
                                   [--runs 5]
"""
from __future__ import annotations

import argparse
import json
import sys
import time

import jax
from physics import settings  # noqa: E402

from mvcoba_jax import runtime  # noqa: E402
from mvcoba_jax.evaluation import runner  # noqa: E402
from mvcoba_jax.evaluation.metrics import case_metrics  # noqa: E402
from mvcoba_jax.evaluation.protocols import PROTOCOLS  # noqa: E402
from mvcoba_jax.evaluation.sources import trained  # noqa: E402
from mvcoba_jax.sim.scenarios import case_to_layout, read_case, stack_layouts  # noqa: E402
from mvcoba_jax.learner.task import Task  # noqa: E402
from mvcoba_jax.suites import suite_files  # noqa: E402
from mvcoba_jax.suites import cases as suite_cases  # noqa: E402


def suite_costs(suite: str, source, runs: int) -> dict:
  cases = [read_case(f) for f in suite_files([suite])[suite]]
  config = suite_cases.suite_config(source.config, suite_cases.pool_for(cases))
  task = Task.build(config, source.views)
  layouts = stack_layouts([case_to_layout(c, task.env) for c in cases for _ in range(runs)])
  keys = jax.random.split(jax.random.PRNGKey(0), len(cases) * runs)
  row = {'suite': suite, 'runs': len(cases) * runs}
  for protocol in ('frozen', 'online'):
    policy = source.actor(config, PROTOCOLS[protocol])
    for timing in ('first_s', 'warm_s'):
      start = time.perf_counter()
      logs = runner.run_logs(runner.evaluate(task, policy, layouts, keys, 60), task)
      row[f'{protocol}_{timing}'] = time.perf_counter() - start
    actions = sum(log.actions for log in logs)
    row[f'{protocol}_actions'] = actions
    row[f'{protocol}_s_per_action'] = row[f'{protocol}_warm_s'] / actions
    row[f'{protocol}_grasp_success'] = case_metrics(logs)['grasp_success']
  row['online_over_frozen_wall'] = row['online_warm_s'] / row['frozen_warm_s']
  row['online_over_frozen_per_action'] = (row['online_s_per_action']
                                          / row['frozen_s_per_action'])
  return row


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--checkpoint', required=True, help='a training work directory or export')
  parser.add_argument('--suite', nargs='+', default=['dev-ordered', 'dev-occluded'])
  parser.add_argument('--runs', type=int, default=5, help='runs per case')
  args = parser.parse_args()
  runtime.setup()
  source = trained(args.checkpoint)
  rows = [suite_costs(s, source, args.runs) for s in args.suite]
  json.dump({'benchmark': 'online_eval', 'settings': settings() | {
      'checkpoint': args.checkpoint, 'runs': args.runs, 'max_actions': 60}, 'results': rows},
      sys.stdout, indent=1)
  print()


if __name__ == '__main__':
  main()
