"""The recipe study's table: per variant (and method, where the study trained several), each
validation suite's grasp success, completion and objects picked, mean over seeds and cases with
the 95% t interval over the per-seed means (`evaluation/intervals.py`), and the training time,
from what `recipe_study.py` wrote.

  python experiments/recipe_table.py [--workdir runs/recipe] [--metrics grasp_success ...]

Prints Markdown; a variant evaluated from one seed so far gets its mean and no interval.
"""
from __future__ import annotations

import argparse
import json
import pathlib
import statistics

from recipe_study import ROOT, VARIANTS

from mvcoba_jax.evaluation import report

METRICS = ('grasp_success', 'completion', 'objects_picked')


def training_minutes(log: pathlib.Path) -> dict[str, float]:
  """variant -> median minutes of its finished training runs (study.jsonl)."""
  times = {}
  for line in log.read_text().splitlines():
    entry = json.loads(line)
    if entry['what'].startswith('train-') and entry['rc'] == 0:
      variant = entry['what'][len('train-'):].rsplit('-s', 1)[0]
      times.setdefault(variant, []).append(entry['wall_s'] / 60)
  return {v: statistics.median(t) for v, t in times.items()}


def by_suite_name(folders: list[str]) -> dict:
  """The rows of each evaluation folder joined by the suite's folder name, each labelled with its
  folder: a study resumed from another checkout names another path for the same suite, and its
  seeds must still meet in one row."""
  merged = {}
  for folder in folders:
    for suite, rows in report.joined_report([folder]).items():
      merged.setdefault(pathlib.Path(suite).name, {}).update(
          {f'{label} ({pathlib.Path(folder).name})': row for label, row in rows.items()})
  return merged


def table(work: pathlib.Path, metrics=METRICS) -> str:
  evaluations = {}
  for folder in sorted((work / 'eval').iterdir()):
    if (folder / 'done').is_file():
      evaluations.setdefault(folder.name.rsplit('-s', 1)[0], []).append(str(folder))
  minutes = training_minutes(work / 'study.jsonl')
  order = lambda row: (list(VARIANTS).index(row.split('-')[0]), row)
  joined = {row: by_suite_name(evaluations[row])
            for row in sorted(evaluations, key=order) if row.split('-')[0] in VARIANTS}
  suites = list(dict.fromkeys(suite for by_suite in joined.values() for suite in by_suite))
  lines = []
  for variant, by_suite in joined.items():
    cells = []
    for suite in suites:  # a suite a variant was not evaluated on reads '-'
      over = report.seed_intervals(by_suite.get(suite, {}), minimum=1)
      entry = next(iter(over.values()), {})
      cells += [report.interval_cell(entry.get(m)) for m in metrics]
    seeds = len(evaluations[variant])
    took = f'{minutes[variant]:.1f}' if variant in minutes else '-'
    lines.append(f'| {variant} | {seeds} | ' + ' | '.join(cells) + f' | {took} |')
  head = ('| variant | seeds | ' + ' | '.join(f'{s}: {m.replace("_", " ")}' for s in suites
                                             for m in metrics)
          + ' | training (min) |\n|---|---|' + '---|' * (len(suites) * len(metrics) + 1))
  return '\n'.join([head] + lines)


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--workdir', default='runs/recipe')
  parser.add_argument('--metrics', nargs='+', default=list(METRICS))
  args = parser.parse_args()
  print(table((ROOT / args.workdir).resolve(), args.metrics))


if __name__ == '__main__':
  main()
