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

from recipe_variants import ROOT, VARIANTS

from mvcoba_jax.evaluation import paper, report

METRICS = ('grasp_success', 'completion', 'objects_picked')
# The per-method screen (issue 52): each method on every preset at the reproduction's 3000
# actions. A preset other than BASE wins only by TIE_MARGIN points or more; two seeds
# give no interval that could separate presets, so the margin guards against choosing noise.
SCREEN = {'reproduction': 'preset_default', 'authors': 'preset_authors',
          'paper_text': 'preset_paper_text'}
BASE = 'reproduction'  # the preset a tie goes to
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


def evaluations(*works: pathlib.Path, kinds=('eval',)) -> dict[str, list[str]]:
  """row (VARIANT or VARIANT-METHOD) -> its finished evaluation folders, one per seed and kind
  (`kinds`: eval/, and eval-high/ of the suites evaluated apart later); a run evaluated in
  several of `works`, as a study and its landed copy, counts once."""
  found = {}
  for work in works:
    for kind in kinds:
      for folder in sorted((work / kind).iterdir()) if (work / kind).is_dir() else []:
        if (folder / 'done').is_file():
          found.setdefault((kind, folder.name), str(folder))
  rows = {}
  for kind, name in sorted(found, key=lambda key: (key[1], kinds.index(key[0]))):
    rows.setdefault(name.rsplit('-s', 1)[0], []).append(found[kind, name])
  return rows


def screen_scores(*works: pathlib.Path) -> dict[str, dict[str, list[float]]]:
  """method -> preset of SCREEN -> each evaluated seed's score: its grasp success averaged over
  the validation suites and their cases."""
  scores = {}
  for row, folders in evaluations(*works).items():
    variant, _, method = row.partition('-')
    preset = next((p for p, v in SCREEN.items() if v == variant), None)
    if preset is None:
      continue
    per_suite = [next(iter(report.seed_intervals(r, minimum=1).values()))['per_seed']
                 ['grasp_success'] for r in by_suite_name(folders).values()]
    scores.setdefault(method or 'mvcoba', {})[preset] = [statistics.mean(s)
                                                         for s in zip(*per_suite)]
  return {m: scores[m] for m in sorted(scores, key=list(paper.PAPER_NAMES).index)}


def _bounds(seeds: list[float]) -> tuple[float, float]:
  """The lowest and highest score the preset can end with, its missing seeds at 0 and at 100."""
  missing = max(SCREEN_SEEDS - len(seeds), 0)
  return statistics.mean(seeds + [0.0] * missing), statistics.mean(seeds + [100.0] * missing)


def ruled_out(scores: dict[str, list[float]]) -> set[str]:
  """The presets (never BASE) that cannot be chosen whatever the seeds still to run score:
  even at 100 they stay below BASE's lowest outcome plus TIE_MARGIN, or below another
  preset's lowest. Their missing seeds cannot change the choice, so the screen does not run
  them."""
  bounds = {p: _bounds(scores.get(p, [])) for p in SCREEN}
  return {p for p in SCREEN if p != BASE and (
      bounds[p][1] < bounds[BASE][0] + TIE_MARGIN
      or any(bounds[p][1] < bounds[q][0] for q in SCREEN if q != p))}


def choose(scores: dict[str, list[float]]) -> str | None:
  """The preset a method trains with: the best mean score, unless it beats BASE's by less
  than TIE_MARGIN points (a tie: BASE); None while BASE, or a preset not ruled out,
  lacks a seed."""
  out = ruled_out(scores)
  open_ = [p for p in SCREEN if p not in out]
  if any(len(scores.get(p, [])) < SCREEN_SEEDS for p in open_):
    return None
  means = {p: statistics.mean(scores[p]) for p in open_}
  best = max(means, key=means.get)
  return best if means[best] - means[BASE] >= TIE_MARGIN else BASE


def choice_table(work: pathlib.Path) -> str:
  """Markdown: each method's score per preset (mean, with the number of seeds) and its choice."""
  head = ('| method | ' + ' | '.join(SCREEN) + ' | trains with |\n|---|'
          + '---|' * (len(SCREEN) + 1))
  lines = []
  for method, scores in screen_scores(work).items():
    out = ruled_out(scores)
    cells = [f'{statistics.mean(scores[p]):.1f} ({len(scores[p])})' if scores.get(p) else '-'
             for p in SCREEN]
    cells = [c + (', ruled out' if p in out else '') for c, p in zip(cells, SCREEN)]
    lines.append(f'| {method} | ' + ' | '.join(cells) + f' | {choose(scores) or "(open)"} |')
  return '\n'.join([head] + lines + ['', f'Score: grasp success averaged over the validation '
                                     f'suites, seeds (in brackets) and cases. A preset other '
                                     f'than {BASE} wins by {TIE_MARGIN:g} points or more; '
                                     f'"ruled out": it cannot be chosen whatever its seeds still '
                                     f'to run score, and they are not run.'])


def table(work: pathlib.Path, metrics=METRICS, kinds=('eval',)) -> str:
  evaluations_of = evaluations(work, kinds=kinds)
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
    seeds = len({pathlib.Path(f).name for f in evaluations_of[variant]})
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
  parser.add_argument('--kinds', nargs='+', default=['eval'],
                      help='the folders of evaluations to join: eval, and eval-high of the '
                           'validation suites evaluated apart later')
  parser.add_argument('--choose', action='store_true',
                      help='each screened method\'s score per preset and the preset it trains with')
  args = parser.parse_args()
  work = (ROOT / args.workdir).resolve()
  print(choice_table(work) if args.choose else table(work, args.metrics, tuple(args.kinds)))


if __name__ == '__main__':
  main()
