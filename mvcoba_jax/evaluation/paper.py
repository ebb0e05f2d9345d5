"""The paper's results (MV-COBA, Sustainability 2021, Tables 1-4: means over each suite's cases)
and their table beside ours, with our intervals over training seeds."""
from __future__ import annotations

import math

from mvcoba_jax.evaluation import intervals, report

# Our method -> the paper's name for it (grasp-only stands for its DRGP).
PAPER_NAMES = {'mvcoba': 'MV-COBA', 'mvcoba_2fcn': 'MV-COBA-2FCNs', 'vpg': 'VPG',
               'grasp_only': 'DRGP', 'mvp': 'MVP', 'cpg': 'CPG'}

# suite -> paper method -> metric -> value (%). Completion is held against our runs completed:
# VPG's counts runs cleared; the paper does not define its own, and its occluded completion of 0.0
# for methods that grasp 26-44 % of the time cannot be a share of objects picked. The figures
# come from other simulators (V-REP), other cases (the authors' own, VPG's for 'vpg') and, in the
# paper, an ImageNet-pretrained DenseNet: beside ours for orientation, never a comparison.
RESULTS = {
    'random': {
        'MV-COBA': {'grasp_success': 83.6, 'action_efficiency': 75.0, 'completion': 94.0},
        'MV-COBA-2FCNs': {'grasp_success': 70.8, 'action_efficiency': 60.4, 'completion': 80.1},
        'VPG': {'grasp_success': 65.4, 'action_efficiency': 51.1, 'completion': 70.9},
        'CPG': {'grasp_success': 64.5, 'action_efficiency': 48.7, 'completion': 67.0},
        'DRGP': {'grasp_success': 56.6, 'action_efficiency': 56.6, 'completion': 44.6},
        'MVP': {'grasp_success': 57.8, 'action_efficiency': 57.8, 'completion': 50.5}},
    'ordered': {
        'MV-COBA': {'grasp_success': 86.3, 'action_efficiency': 80.4, 'completion': 100.0},
        'MV-COBA-2FCNs': {'grasp_success': 76.4, 'action_efficiency': 68.7, 'completion': 91.6},
        'VPG': {'grasp_success': 65.2, 'action_efficiency': 49.5, 'completion': 78.8},
        'CPG': {'grasp_success': 63.5, 'action_efficiency': 53.0, 'completion': 83.1},
        'DRGP': {'grasp_success': 42.3, 'action_efficiency': 42.3, 'completion': 20.6},
        'MVP': {'grasp_success': 35.6, 'action_efficiency': 35.6, 'completion': 27.2}},
    'occluded': {
        'MV-COBA': {'grasp_success': 97.8, 'completion': 100.0},
        'MV-COBA-2FCNs': {'grasp_success': 26.2, 'completion': 0.0},
        'VPG': {'grasp_success': 28.3, 'completion': 0.0},
        'CPG': {'grasp_success': 29.7, 'completion': 0.0},
        'DRGP': {'grasp_success': 26.3, 'completion': 0.0},
        'MVP': {'grasp_success': 44.3, 'completion': 0.0}},
    # VPG (Zeng et al., IROS 2018), Table II: its 11 public hard cases, runs completed; its grasp
    # success and action efficiency are means over completed runs.
    'vpg': {'VPG': {'grasp_success': 77.2, 'action_efficiency': 60.1, 'completion': 82.7}},
}
# (our metric, the paper's figure it is held against, the column). The paper's grasp success and
# action efficiency are means over completed runs of each run's rate (the authors' evaluate.py):
# ours are given both pooled over every attempt of every run and that way.
COLUMNS = (('grasp_success', 'grasp_success', 'grasp success'),
           ('grasp_success_per_run', 'grasp_success', 'grasp success per completed run'),
           ('action_efficiency', 'action_efficiency', 'action efficiency'),
           ('action_efficiency_per_run', 'action_efficiency',
            'action efficiency per completed run'),
           ('objects_picked', None, 'objects picked'),
           ('completion', 'completion', 'runs completed (paper: completion)'))


def paper_name(group: str) -> str:
  """The paper's name of a row group of `report.training_groups` (`mvcoba {...}` ->
  `MV-COBA {...}`)."""
  method = report.method_of(group)
  return PAPER_NAMES.get(method, method) + group[len(method):]


def comparison(suite: str, ours: dict[str, dict]) -> str:
  """Markdown: per method, our mean [95% CI over seeds] and the paper's figure, per metric, and
  each seed's grasp success.

  `ours` is `report.seed_intervals` of the suite (method -> metric -> (point, low, high))."""
  head = ('| method | seeds | ' + ' | '.join(f'{label}: ours | paper' for *_, label in COLUMNS)
          + ' | grasp success per seed |\n|---|---|' + '---|---|' * len(COLUMNS) + '---|')
  lines = [head]
  paper = RESULTS.get(suite, {})
  for method, entry in ours.items():
    name = PAPER_NAMES.get(report.method_of(method), method)
    cells = []
    for key, paper_key, _ in COLUMNS:
      ci = report.interval_cell(entry.get(key))
      theirs = paper.get(name, {}).get(paper_key) if paper_key else None
      cells += [ci, '-' if theirs is None else f'{theirs:.1f}']
    cells.append(report.per_seed_cell(entry['per_seed']['grasp_success']))
    lines.append(f'| {name} ({method}) | {entry["seeds"]} | ' + ' | '.join(cells) + ' |')
  for name, figures in paper.items():
    if name not in {PAPER_NAMES.get(report.method_of(m)) for m in ours}:
      cells = []
      for _, paper_key, _ in COLUMNS:
        cells += ['-', '-' if paper_key not in figures else f'{figures[paper_key]:.1f}']
      lines.append(f'| {name} (not run) | - | ' + ' | '.join(cells) + ' | - |')
  return '\n'.join(lines)


def separations(ours: dict[str, dict]) -> str:
  """Markdown: per metric, which methods beat which in a suite, the only claims we make: their
  intervals over seeds are disjoint with `intervals.CLAIM_SEEDS` seeds or more behind each
  (`intervals.separated`), each with its gap (the higher's low end less the lower's high end, in
  points: a claim that hangs by a hair says so). Pairs not named are not distinguishable at
  this sample size."""
  few = sorted({paper_name(m) for m, e in ours.items() if e['seeds'] < intervals.CLAIM_SEEDS})
  lines = [f'- fewer than {intervals.CLAIM_SEEDS} seeds, so no claim about: {", ".join(few)} '
           '(their per-seed means are above)'] if few else []
  for key, label in (('grasp_success', 'grasp success'), ('completion', 'completion'),
                     ('objects_picked', 'objects picked')):
    scored = sorted(((e[key], e['seeds'], m) for m, e in ours.items() if e.get(key) is not None),
                    key=lambda entry: -entry[0][0])
    beats = []
    for i, (high, seeds, method) in enumerate(scored):
      below = [f'{paper_name(m)} (gap {high[1] - low[2]:.2f})' for low, others, m in scored[i + 1:]
               if intervals.separated(high, low, (seeds, others))]
      if below:
        beats.append(f'{paper_name(method)} > {", ".join(below)}')
    lines.append(f'- {label}: ' + ('; '.join(beats) if beats else
                                   'no two methods distinguishable'))
  return '\n'.join(lines)


def comparisons(results: dict[str, dict]) -> str:
  """Markdown of every suite of an evaluation's results.json: `comparison` of its methods' means
  and intervals over seeds (`report.seed_intervals`) with the paper's figures, and the
  `separations` those intervals allow."""
  parts = []
  for suite, rows in results.items():
    ours = report.seed_intervals(rows, minimum=1)
    seeds = sorted({entry['seeds'] for entry in ours.values()})
    parts.append(f'### {suite}: mean [95% CI over {"/".join(map(str, seeds))} seeds] and the '
                 f'paper\n\n' + comparison(suite, ours)
                 + '\n\nWhere our intervals separate (A > B: disjoint, A higher):\n\n'
                 + separations(ours))
  return '\n\n'.join(parts)


# A README table's columns per suite: (our metric, the reference figure in its own column after
# it or None, its label, whether it shows our interval), in whole per cent. The paper's suites:
# grasp success and objects picked (the paper's completion, undefined in its text, stays in
# `comparisons` beside runs completed); VPG's hard cases against VPG's own table: runs
# completed, grasp success pooled and per completed run (VPG's), action efficiency per completed
# run (VPG's).
SUMMARY = (('grasp_success', 'grasp_success', 'grasp', True),
           ('objects_picked', None, 'picked', False))
VPG_SUMMARY = (('completion', 'completion', 'completed', True),
               ('grasp_success', None, 'grasp', True),
               ('grasp_success_per_run', 'grasp_success', 'per completed run', True),
               ('action_efficiency_per_run', 'action_efficiency', 'efficiency per completed run',
                True))


def summary(results: dict[str, dict], suites=('random', 'ordered', 'occluded'),
            columns=SUMMARY, reference: str = 'paper') -> str:
  """Markdown of one compact table for a README: per method (rows) and suite, our `columns`
  (`SUMMARY`, `VPG_SUMMARY`), the interval over seeds where a column asks for it, each followed
  by the `reference`'s figure (the paper's, or VPG's) in a column of its own where the column names
  one, in whole per cent. The full tables are `comparisons`."""
  over = {suite: report.seed_intervals(results[suite], minimum=1) for suite in suites
          if suite in results}
  labels = []
  for _, paper_key, label, _ in columns:
    labels += [label, reference] if paper_key else [label]
  head = ('| method | seeds | '
          + ' | '.join(f'{s}: {labels[0]} | ' + ' | '.join(labels[1:]) for s in over)
          + ' |\n|---|---|' + '---|' * len(labels) * len(over))
  whole = lambda v: f'{v:.0f}'
  lines = [head]
  for method in dict.fromkeys(m for rows in over.values() for m in rows):
    name = PAPER_NAMES.get(report.method_of(method), method)  # whose figures are the paper's
    cells, seeds = [], set()
    for suite, rows in over.items():
      entry, paper = rows.get(method) or {}, RESULTS.get(suite, {}).get(name, {})
      seeds.add(entry.get('seeds'))
      for key, paper_key, _, interval in columns:
        ours = entry.get(key)
        cells.append('-' if ours is None else whole(ours[0]) + (
            f' [{whole(ours[1])}, {whole(ours[2])}]' if interval and not math.isnan(ours[1])
            else ''))
        if paper_key:
          cells.append(whole(paper[paper_key]) if paper_key in paper else '')
    count = '/'.join(str(s) for s in sorted(s for s in seeds if s))
    lines.append(f'| {report.cell(paper_name(method))} | {count} | ' + ' | '.join(cells) + ' |')
  return '\n'.join(lines)
