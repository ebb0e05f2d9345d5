"""Learning of training runs side by side: grasp success over the last `--window` grasps per run
and per group, and one PNG of the curves (each run thin, each group's mean thick).

  python benchmarks/compare_runs.py --group network runs/a-s0 runs/a-s1 --group acting runs/b-s0 \
      [--window 200] [--png curves.png]

Prints one JSON object. A run's curve is the paper's windowed grasp success (`curves.py`) against
training actions, read from its actions.jsonl.
"""
from __future__ import annotations

import argparse
import json
import pathlib

import numpy as np
from matplotlib.figure import Figure

from mvcoba_jax.learner import curves


def read(workdir: pathlib.Path) -> dict:
  records = [json.loads(line) for line in (workdir / 'actions.jsonl').read_text().splitlines()]
  grasps = [r for r in records if r['primitive'] == 'grasp']
  summary = json.loads((workdir / 'eval_summary.json').read_text()) \
      if (workdir / 'eval_summary.json').exists() else None
  return {'records': records, 'grasps': grasps, 'greedy': summary}


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--group', nargs='+', action='append', required=True,
                      metavar=('NAME', 'WORKDIR'), help='a name and its runs\' work directories')
  parser.add_argument('--window', type=int, default=200)
  parser.add_argument('--png', default='curves.png')
  args = parser.parse_args()
  fig = Figure(figsize=(8, 4.5))
  ax = fig.subplots()
  out = {}
  for (name, *dirs), color in zip(args.group, ('tab:blue', 'tab:orange', 'tab:green', 'tab:red')):
    rows, series = {}, []
    for d in dirs:
      run = read(pathlib.Path(d))
      grasp_success, _ = curves.on_actions([r['primitive'] == 'grasp' for r in run['records']],
                                           [r['grasp_success'] for r in run['records']],
                                           args.window)
      ax.plot(np.arange(1, len(grasp_success) + 1), 100 * grasp_success, color=color, alpha=0.3,
              linewidth=0.8)
      series.append(grasp_success)
      last = run['grasps'][-args.window:]
      rows[d] = {'actions': len(run['records']), 'grasps': len(run['grasps']),
                 'pushes': len(run['records']) - len(run['grasps']),
                 f'last_{args.window}_grasp_success': 100 * np.mean([r['grasp_success']
                                                                    for r in last]),
                 'greedy_check': run['greedy']}
    length = min(len(s) for s in series)
    mean = np.mean([s[:length] for s in series], axis=0)
    ax.plot(np.arange(1, length + 1), 100 * mean, color=color, linewidth=2,
            label=f'{name} (mean of {len(dirs)})')
    key = f'last_{args.window}_grasp_success'
    out[name] = {'runs': rows, f'mean_{key}': float(np.mean([r[key] for r in rows.values()]))}
  ax.set(xlabel='training actions', ylabel=f'grasp success, last {args.window} grasps (%)',
         ylim=(0, 100))
  ax.grid(alpha=0.3)
  ax.legend()
  fig.tight_layout()
  fig.savefig(args.png, dpi=100)
  print(json.dumps({'benchmark': 'compare_runs', 'window': args.window, 'png': args.png,
                    'groups': out}, indent=1))


if __name__ == '__main__':
  main()
