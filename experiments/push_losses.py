"""Objects lost against pushes made, run by run: from evaluations' results.json (every run's
actions, grasps and objects lost), the runs of one suite grouped by how many pushes they made,
with the objects each group lost per run, and the correlation over runs.

  python experiments/push_losses.py RESULTS.json ... [--suite random] > push-losses.md
"""
from __future__ import annotations

import argparse
import pathlib
import sys

import numpy as np

from mvcoba_jax.evaluation import report

GROUPS = ((0, 0), (1, 1), (2, 2), (3, 4), (5, None))


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('results', nargs='+')
  parser.add_argument('--suite', default='dev-random')
  args = parser.parse_args()
  pushes, lost = [], []
  for path in args.results:
    try:
      suites = report.read_results(pathlib.Path(path))
    except report.ResultsError as e:
      sys.exit(f'push_losses: {e}')
    # a validation suite is keyed by its folder's path: match its name
    rows = next((rows for key, rows in suites.items()
                 if key.rstrip('/').split('/')[-1] == args.suite), None)
    if rows is None:
      raise SystemExit(f'{path}: no suite {args.suite} (it has {", ".join(suites)})')
    for row in rows.values():
      for case in row['runs'].values():
        for run in case:
          pushes.append(run['actions'] - run['grasp_attempts'])
          lost.append(run['lost'])
  pushes, lost = np.array(pushes), np.array(lost)
  print(f'{len(pushes)} runs of {args.suite} from {len(args.results)} evaluations; correlation '
        f'of pushes and objects lost over runs: {np.corrcoef(pushes, lost)[0, 1]:.2f}\n')
  print('| pushes in the run | runs | objects lost per run |')
  print('|---|---|---|')
  for low, high in GROUPS:
    chosen = (pushes >= low) & (pushes <= (np.inf if high is None else high))
    label = f'{low}' if low == high else (f'{low} or more' if high is None else f'{low}-{high}')
    mean = f'{lost[chosen].mean():.2f}' if chosen.any() else '-'
    print(f'| {label} | {chosen.sum()} | {mean} |')


if __name__ == '__main__':
  main()
