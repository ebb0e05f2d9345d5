"""The recipe study's table: per variant (and method, where the study trained several), each
validation suite's grasp success, completion and objects picked, mean over seeds and cases with
the 95% t interval over the per-seed means (`evaluation/intervals.py`), and the training time,
from what `recipe_study.py` wrote.

  python experiments/recipe_table.py [--workdir runs/recipe] [--metrics grasp_success ...]
  python experiments/recipe_table.py --workdir docs/results/recipe/baselines --choose

Prints Markdown; a variant evaluated from one seed so far gets its mean and no interval.
`--choose` prints instead each method's score on every preset of the per-method screen and the
preset the reproduction trains it with (`choose`, the rule of docs/results/recipe.md).
"""
from __future__ import annotations

import argparse
import json
import pathlib
import statistics

from recipe_study import ROOT, VARIANTS

from mvcoba_jax.evaluation import paper, report

METRICS = ('grasp_success', 'completion', 'objects_picked')
# The per-method screen (issue 52): each method on every preset at the reproduction's 3000
# actions. A preset other than `default` wins only by more than TIE_MARGIN points; two seeds
# give no interval that could separate presets, so the margin guards against choosing noise.
SCREEN = {'default': 'preset_default', 'authors': 'preset_authors',
          'paper_text': 'preset_paper_text'}
SCREEN_SEEDS = 2
TIE_MARGIN = 3.0


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


def evaluations(work: pathlib.Path) -> dict[str, list[str]]:
  """row (VARIANT or VARIANT-METHOD) -> its finished evaluation folders, one per seed."""
  rows = {}
  for folder in sorted((work / 'eval').iterdir()):
    if (folder / 'done').is_file():
      rows.setdefault(folder.name.rsplit('-s', 1)[0], []).append(str(folder))
  return rows


def screen_scores(work: pathlib.Path) -> dict[str, dict[str, float]]:
  """method -> preset -> its score: grasp success averaged over the validation suites, seeds and
  cases, for the methods evaluated from SCREEN_SEEDS seeds on every preset of SCREEN."""
  rows, scores = evaluations(work), {}
  for row, folders in rows.items():
    variant, _, method = row.partition('-')
    preset = next((p for p, v in SCREEN.items() if v == variant), None)
    if preset is None or len(folders) < SCREEN_SEEDS:
      continue
    means = [report.seed_intervals(r, minimum=1) for r in by_suite_name(folders).values()]
    scores.setdefault(method or 'mvcoba', {})[preset] = statistics.mean(
        next(iter(m.values()))['grasp_success'][0] for m in means)
  return {m: scores[m] for m in sorted(scores, key=list(paper.PAPER_NAMES).index)
          if len(scores[m]) == len(SCREEN)}


def choose(scores: dict[str, float]) -> str:
  """The preset a method trains with: the best score, unless it beats `default`'s by less than
  TIE_MARGIN points (a tie, `default`)."""
  best = max(scores, key=scores.get)
  return best if scores[best] - scores['default'] >= TIE_MARGIN else 'default'


def choice_table(work: pathlib.Path) -> str:
  scores = screen_scores(work)
  head = ('| method | ' + ' | '.join(SCREEN) + ' | trains with |\n|---|'
          + '---|' * (len(SCREEN) + 1))
  return '\n'.join([head] + [f'| {m} | ' + ' | '.join(f'{s[p]:.1f}' for p in SCREEN)
                             + f' | {choose(s)} |' for m, s in scores.items()])


def table(work: pathlib.Path, metrics=METRICS) -> str:
  evaluations_of = evaluations(work)
  minutes = training_minutes(work / 'study.jsonl')
  order = lambda row: (list(VARIANTS).index(row.split('-')[0]), row)
  joined = {row: by_suite_name(evaluations_of[row])
            for row in sorted(evaluations_of, key=order) if row.split('-')[0] in VARIANTS}
  suites = list(dict.fromkeys(suite for by_suite in joined.values() for suite in by_suite))
  lines = []
  for variant, by_suite in joined.items():
    cells = []
    for suite in suites:  # a suite a variant was not evaluated on reads '-'
      over = report.seed_intervals(by_suite.get(suite, {}), minimum=1)
      entry = next(iter(over.values()), {})
      cells += [report.interval_cell(entry.get(m)) for m in metrics]
    seeds = len(evaluations_of[variant])
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
  parser.add_argument('--choose', action='store_true',
                      help='each screened method\'s score per preset and the preset it trains with')
  args = parser.parse_args()
  work = (ROOT / args.workdir).resolve()
  print(choice_table(work) if args.choose else table(work, args.metrics))


if __name__ == '__main__':
  main()
