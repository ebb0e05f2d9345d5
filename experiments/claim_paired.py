"""Two recipes' claims compared seed by seed: each claim's results.json (`mvcoba-eval` over the
same seeds' checkpoints, `recipe/winning/claim/claim.sh`) gives every suite's grasp success, runs
completed and objects picked per seed and case; the table holds each recipe's mean with its
interval over the seeds and the candidate less the baseline paired by seed (the seed's luck in
the suites' cases cancels only where both recipes trained the same seeds, so seeds are matched by
their run name, `...-sN`: a row's settings hold the evaluation's seed, not the training's), and
the objects each lost (runs with a loss).

  python experiments/claim_paired.py CANDIDATE/results.json BASELINE/results.json \
    [--names candidate baseline] > paired.md
"""
from __future__ import annotations

import argparse
import pathlib
import re
import sys

from mvcoba_jax.evaluation import intervals, report

METRICS = (('grasp_success', 'grasp success'), ('completion', 'runs completed'),
           ('objects_picked', 'objects picked'))
RATE = (0.0, 100.0)


def by_seed(suite: dict) -> dict:
  """seed -> that seed's row (its cases and runs), from a suite's rows named `... (RUN-sN)`."""
  rows = {}
  for name, row in suite.items():
    match = re.search(r'-s(\d+)\)?$', name)
    if not match:
      raise SystemExit(f'{name}: not a run name ending in -sSEED')
    rows[int(match.group(1))] = row
  return rows


def scores(rows: dict, seeds: list[int], metric: str) -> list[list[float]]:
  return [[rows[s]['cases'][c][metric] for c in sorted(rows[s]['cases'])] for s in seeds]


def losses(rows: dict, seeds: list[int]) -> str:
  runs = [run for s in seeds for case in rows[s]['runs'].values() for run in case]
  return (f'{sum(r["lost"] for r in runs)} ({sum(r["lost"] > 0 for r in runs)} of '
          f'{len(runs)})')


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('candidate')
  parser.add_argument('baseline')
  parser.add_argument('--names', nargs=2, default=('candidate', 'baseline'))
  args = parser.parse_args()
  try:
    candidate = report.read_results(pathlib.Path(args.candidate))
    baseline = report.read_results(pathlib.Path(args.baseline))
  except report.ResultsError as e:
    sys.exit(f'claim_paired: {e}')
  a, b = args.names
  print(f'| suite | metric | {a} | {b} | {a} - {b}, paired by seed |')
  print('|---|---|---|---|---|')
  lost = []
  for suite in candidate:
    if suite not in baseline:
      continue
    mine, theirs = by_seed(candidate[suite]), by_seed(baseline[suite])
    seeds = sorted(set(mine) & set(theirs))
    for metric, label in METRICS:
      x, y = scores(mine, seeds, metric), scores(theirs, seeds, metric)
      defined = all(v is not None for row in x + y for v in row)
      print(f'| {suite} | {label} | '
            f'{report.interval_cell(intervals.interval(x, within=RATE) if defined else None)} | '
            f'{report.interval_cell(intervals.interval(y, within=RATE) if defined else None)} | '
            f'{report.interval_cell(intervals.paired(x, y) if defined else None)} |')
    lost.append(f'{suite}: {losses(mine, seeds)} against {losses(theirs, seeds)}')
  print(f'\nObjects lost, {a} against {b} (runs with a loss): ' + '; '.join(lost) + '.')


if __name__ == '__main__':
  main()
