"""Evaluation results: per-method rows scored from per-run counts, the paper's tables in Markdown,
results.json/results.md written atomically, and earlier results joined into one report."""
from __future__ import annotations

import dataclasses
import json
import math
import os
import pathlib

import numpy as np

from mvcoba_jax import config as config_lib
from mvcoba_jax.config import Error
from mvcoba_jax.evaluation import intervals, metrics
from mvcoba_jax.evaluation.protocols import PROTOCOLS, labelled

METRICS = (('grasp_success', 'grasp success (%)'), ('action_efficiency', 'action efficiency (%)'),
           ('completion', 'completion (%)'), ('objects_picked', 'objects picked (%)'),
           ('grasp_to_push', 'grasp-to-push ratio'),
           ('grasp_success_per_run', 'grasp success, mean per completed run (%)'),
           ('action_efficiency_per_run', 'action efficiency, mean per completed run (%)'),
           ('repeated_failures', 'repeated failed actions per run'))
# What each metric can take: rates in %, the others counts or ratios.
RANGES = {key: (0.0, 100.0) if label.endswith('(%)') else (0.0, math.inf) for key, label in METRICS}


class ResultsError(Error):
  """An earlier evaluation's results.json that --tables cannot use."""


def distinct_names(paths: list[str]) -> list[str]:
  """Per path, the fewest trailing parts of its absolute path that no other path of `paths` ends
  with (`a/train`, `b/train` -> `a/train`, `b/train`; `runs/s0`, `runs/s1` -> `s0`, `s1`).

  Raises ResultsError for a folder given twice: it would be counted as two policies or seeds.
  """
  parts = [pathlib.Path(p).resolve().parts for p in paths]
  first = {}
  for p, path in zip(parts, paths):
    if p in first:
      raise ResultsError(f'{path} is given twice (also as {first[p]}); each folder counts once')
    first[p] = path
  names = []
  for i, p in enumerate(parts):
    n = 1
    while any(q[-n:] == p[-n:] for j, q in enumerate(parts) if j != i):
      n += 1
    names.append('/'.join(p[-n:]))
  return names


def row_labels(directories: list[str], methods: list[str]) -> list[str]:
  """Table rows of the checkpoints, one each: the method, and when a method repeats, as much of
  each folder's path as tells it apart from the method's other folders."""
  distinct_names(directories)  # refuses a folder given twice
  labels = list(methods)
  for method in {m for m in methods if methods.count(m) > 1}:
    mine = [i for i, m in enumerate(methods) if m == method]
    for i, name in zip(mine, distinct_names([directories[i] for i in mine])):
      labels[i] = f'{method} ({name})'
  return labels


def json_safe(tree):
  """`tree` with NaN and infinities (undefined metrics) as null, which JSON can hold."""
  if isinstance(tree, dict):
    return {k: json_safe(v) for k, v in tree.items()}
  return None if isinstance(tree, float) and not math.isfinite(tree) else tree


def cell(text: str) -> str:
  """`text` as one Markdown table cell: a '|' in a case or folder name escaped, a line break
  made a space."""
  return str(text).replace('\\', '\\\\').replace('|', '\\|').replace('\n', ' ')


def table(rows: dict[str, dict[str, dict]], key: str, label: str, cases: list[str]) -> str:
  """A Markdown table: methods as rows, cases and their mean as columns ('-': undefined/not run)."""
  head = (f'| {label} | ' + ' | '.join(map(cell, cases)) + ' | mean |\n|---|'
          + '---|' * (len(cases) + 1))
  lines = [head]
  for method, result in rows.items():
    cells = [result['cases'].get(c, {}).get(key, math.nan) for c in cases] + [result['mean'][key]]
    lines.append(f'| {cell(method)} | ' + ' | '.join('-' if not math.isfinite(v) else f'{v:.1f}'
                                                      for v in cells) + ' |')
  return '\n'.join(lines)


def suite_tables(suite: str, rows: dict[str, dict]) -> list[str]:
  """One Markdown table per metric of a suite (its columns are every case any method ran), after
  the table of intervals over training seeds when a method was evaluated from several."""
  cases = list(dict.fromkeys(c for result in rows.values() for c in result['cases']))
  tables = [f'### {suite}: {label}\n\n' + table(rows, key, label, cases) for key, label in METRICS]
  shaped = {label: row['by_shape'] for label, row in rows.items() if row.get('by_shape')}
  if shaped:
    tables.append(f'### {suite}: by shape: grasp success % (grasps aimed at it) / objects '
                  'picked % / pushes that moved it most\n\n' + shape_table(shaped))
  over_seeds = seed_intervals(rows)
  if over_seeds:
    tables.insert(0, f'### {suite}: over training seeds, mean [95% t interval over '
                  'the per-seed means]\n\n'
                  + interval_table(over_seeds))
  return tables


def method_of(label: str) -> str:
  """The method of a row label (`row_labels` and `seed_intervals` add to it after a space)."""
  return label.split(' ')[0]


def _flat(tree) -> dict:
  """{dotted name: the leaf as JSON} of a config dict."""
  return {k: json.dumps(v) for k, v in config_lib.flat(tree).items()}


def as_trained(training: dict) -> dict:
  """A row's recorded training config with the fields added since it was evaluated at the values
  its run used (`config.LEGACY`, else today's defaults), so that the rows of one training that two
  versions of the code evaluated pool; one that no longer reads as a config stays as recorded."""
  try:
    return config_lib.trained_as(config_lib.from_dict(training))
  except (config_lib.ConfigError, TypeError, ValueError, KeyError, AttributeError):
    return training


def training_groups(rows: dict[str, dict]) -> dict[str, list[str]]:
  """Rows that are one method trained with one config except its seed, named: the method, or
  when it was trained in several configs, the method and the fields where its config differs
  from the value most of them hold (`mvcoba {train.gamma=0.2}`); rows evaluated under another
  protocol than frozen group apart (`mvcoba [online]`, `mvcoba [no-repeat]`). A training seed
  met again in a config (one policy evaluated from two folders) goes to a group of its own, so an
  interval never counts a seed twice. Rows read from results written before evaluation recorded
  the training config (`settings.training`) form a group of their own per method."""
  found, seeds = {}, {}
  for label, result in rows.items():
    settings = result.get('settings') if isinstance(result.get('settings'), dict) else {}
    training = settings.get('training')
    key = json.dumps(as_trained(training), sort_keys=True) if isinstance(training, dict) else None
    protocol = settings.get('protocol')
    method = labelled(method_of(label), None if protocol is None else str(protocol)[:20])
    seen = seeds.setdefault((method, key), [])
    again = seen.count(settings.get('training_seed')) if key is not None else 0
    seen.append(settings.get('training_seed'))
    found.setdefault(method, {}).setdefault((key, again), []).append(label)
  groups = {}
  for method, by_config in found.items():
    if len(by_config) == 1:
      groups[method] = next(iter(by_config.values()))
      continue
    flat = {key: _flat(json.loads(key)) for key, _ in by_config if key is not None}
    usual = {}  # field -> its most common value among the configs (the first met on a tie)
    for f in dict.fromkeys(f for values in flat.values() for f in values):
      seen = [values.get(f, '-') for values in flat.values()]
      usual[f] = max(dict.fromkeys(seen), key=seen.count)
    for (key, again), labels in by_config.items():
      about = ('training config not recorded' if key is None else
               ', '.join(f'{f}={v}' for f, v in flat[key].items() if v != usual[f]))
      about += f'{", " if about else ""}seeds met again ({again})' if again else ''
      groups[f'{method} {{{about}}}' if about else method] = labels
  return groups


def seed_intervals(rows: dict[str, dict], minimum: int = 2) -> dict[str, dict]:
  """Per group of `training_groups` evaluated from `minimum` or more checkpoints (training seeds):
  each metric's mean over seeds and cases with its 95% interval over seeds
  (`intervals.interval`) and each seed's mean (`per_seed`), over the cases every checkpoint ran;
  None where a metric is undefined in some case."""
  out = {}
  for group, labels in training_groups(rows).items():
    results = [rows[label] for label in labels]
    if len(results) < minimum:
      continue
    cases = [c for c in results[0]['cases'] if all(c in r['cases'] for r in results)]
    entry = {'seeds': len(results), 'cases': len(cases), 'per_seed': {}}
    for key, _ in METRICS:
      scores = np.array([[r['cases'][c][key] for c in cases] for r in results], np.float64)
      finite = np.isfinite(scores).all()
      entry[key] = intervals.interval(scores, within=RANGES[key]) if finite else None
      entry['per_seed'][key] = intervals.seed_means(scores).tolist() if finite else None
    out[group] = entry
  return out


def interval_cell(value) -> str:
  """`mean [low, high]` of an interval (the mean alone where one seed gives none; '-' where
  undefined)."""
  if value is None:
    return '-'
  return f'{value[0]:.1f}' if math.isnan(value[1]) else \
      f'{value[0]:.1f} [{value[1]:.1f}, {value[2]:.1f}]'


def per_seed_cell(values) -> str:
  """Each seed's mean, in seed order ('-' where undefined)."""
  return '-' if values is None else ' / '.join(f'{v:.1f}' for v in values)


def interval_table(over_seeds: dict[str, dict]) -> str:
  head = ('| method | seeds | ' + ' | '.join(label for _, label in METRICS)
          + ' | grasp success per seed |\n|---|---|' + '---|' * (len(METRICS) + 1))
  return '\n'.join([head] + [f'| {cell(m)} | {e["seeds"]} | ' + ' | '.join(interval_cell(e[k]) for k, _ in METRICS)
                             + f' | {per_seed_cell(e["per_seed"]["grasp_success"])} |'
                             for m, e in over_seeds.items()])


def shape_table(by_label: dict[str, dict]) -> str:
  """Rows: the labels; columns: every shape any row counted (`metrics.shape_metrics`)."""
  shapes = list(dict.fromkeys(s for row in by_label.values() for s in row))
  head = '| method | ' + ' | '.join(cell(s) for s in shapes) + ' |\n|---|' + '---|' * len(shapes)
  def entry(m):
    if m is None:
      return ''
    rate = lambda v: '-' if math.isnan(v) else f'{v:.1f}'
    return (f'{rate(m["grasp_success"])} ({m["grasps"]}) / {rate(m["objects_picked"])} / '
            f'{m["pushes"]}')
  return '\n'.join([head] + [f'| {cell(label)} | ' + ' | '.join(entry(row.get(s)) for s in shapes)
                             + ' |' for label, row in by_label.items()])


def scored(by_case: dict[str, list[metrics.RunLog]], wall_s: float) -> dict:
  """A method's row of a suite: metrics per case and their means, with the runs they came from."""
  per_case = {name: metrics.case_metrics(logs) for name, logs in by_case.items()}
  row = {'cases': per_case, 'mean': metrics.suite_average(per_case), 'wall_s': wall_s,
         'runs': {name: [dataclasses.asdict(log) for log in logs]
                  for name, logs in by_case.items()}}
  by_shape = metrics.shape_metrics([log for logs in by_case.values() for log in logs])
  return row if by_shape is None else {**row, 'by_shape': by_shape}


def starts(by_case: dict[str, list[metrics.RunLog]], listed: dict[str, int]) -> tuple[str, str]:
  """(every case as `name k/n`, the cases among them that began short): the objects in play at
  the start of the case's runs (one figure when every run began alike, else each run's) of the
  n its file lists. Objects that leave while a case settles are not in play."""
  parts, short = [], []
  for name, logs in by_case.items():
    counts = [log.objects for log in logs]
    text = f'{name} {counts[0] if len(set(counts)) == 1 else ",".join(map(str, counts))}/' \
           f'{listed[name]}'
    parts.append(text)
    if min(counts) < listed[name]:
      short.append(text)
  return ', '.join(parts), ', '.join(short)


def loss_summary(lost: list[dict]) -> str:
  """One line on the objects that left the workspace (see `evaluation.losses`)."""
  grasps = [r for r in lost if r['primitive'] == 'grasp']
  return (f'{len(lost)} objects left the workspace ({len(grasps)} during grasps, '
          f'{len(lost) - len(grasps)} during pushes; '
          f'{sum(r["distance_to_gripper"] <= 0.03 for r in lost)} began within 3 cm of the '
          f'gripper\'s target, {sum(r["margin_to_border"] <= 0.03 for r in lost)} within 3 cm of '
          'the border): losses.json')


def write_report(report: dict, out: pathlib.Path) -> str:
  """Writes results.json and results.md (each replaced whole, never half written); the Markdown.

  Raises ResultsError when a file cannot be written (a full disk): the earlier one is intact.
  """
  text = '\n\n'.join(t for suite, rows in report.items() for t in suite_tables(suite, rows)) + '\n'
  for name, content in (('results.json', json.dumps(json_safe(report), indent=1)),
                        ('results.md', text)):
    write_whole(out / name, content)
  return text


def write_whole(path: pathlib.Path, content: str) -> None:
  """`path` replaced by `content` at once, or left as it was (ResultsError) when the disk or a
  file size limit refuses the write."""
  partial = path.with_name(f'.{path.name}.partial')
  try:
    partial.write_text(content)
    os.replace(partial, path)
  except OSError as e:
    partial.unlink(missing_ok=True)
    raise ResultsError(f'cannot write {path} ({e.strerror}); '
                       f'{"the earlier one is intact" if path.exists() else "nothing written"}'
                       ) from None


def read_results(path: pathlib.Path, purpose: str = '') -> dict:
  """An evaluation's results.json (suite -> row -> result), or ResultsError naming the file."""
  try:
    data = json.loads(path.read_text())
  except (OSError, ValueError, RecursionError) as e:
    raise ResultsError(f'{path}: cannot read evaluation results{purpose} '
                       f'({type(e).__name__}: {str(e)[:120]})') from None
  if not isinstance(data, dict) or not all(isinstance(rows, dict) for rows in data.values()):
    raise ResultsError(f'{path}: not the results of mvcoba-eval (suite -> method -> results)')
  odd = next((name for rows in (data, *data.values()) for name in rows
              if not name.isprintable()), None)
  if odd is not None:
    raise ResultsError(f'{path}: suite or row {odd[:40]!r}: names of one line of text expected')
  return data


def kept_rows(out: pathlib.Path, settings: dict[tuple[str, str], dict]
              ) -> tuple[dict, list, list]:
  """(the rows of `out`/results.json that a resumed evaluation keeps, as a report; the (suite,
  row) of those this invocation does not evaluate; the (suite, row, the settings that differ)
  of those it evaluates again because they were evaluated otherwise): every row evaluated with
  the `settings` of its (suite, row), and every row of another suite, policy or protocol, which
  it leaves as it was. Empty when there is no such file; a kept row that does not hold together
  is refused."""
  path = out / 'results.json'
  if not path.exists():
    return {}, [], []
  data = read_results(path, ' to resume')
  report, others, redone = {}, [], []
  for suite, rows in data.items():
    for label, row in rows.items():
      wanted = settings.get((suite, label))
      if wanted is None:
        others.append((suite, label))
      elif not (isinstance(row, dict) and row.get('settings') == wanted):
        had = row.get('settings') if isinstance(row, dict) else None
        had = had if isinstance(had, dict) else {}
        redone.append((suite, label, sorted(k for k in wanted if had.get(k) != wanted[k])))
        continue
      report.setdefault(suite, {})[label] = rescored(row, f'{path}: {suite}/{label}')
  return report, others, redone


def in_order(report: dict, keys) -> dict:
  """`report` with the (suite, row) `keys` first, in their order, then its other rows as they
  were."""
  ordered = {}
  for suite, label in keys:
    if label in report.get(suite, {}):
      ordered.setdefault(suite, {})[label] = report[suite][label]
  for suite, rows in report.items():
    for label, row in rows.items():
      ordered.setdefault(suite, {}).setdefault(label, row)
  return ordered


def joined_report(folders: list[str]) -> dict:
  """The results.json of earlier evaluations as one report, scored again from their runs.

  A row label met again in a suite gets after it as much of its --out folder's path as tells
  the folders apart; a folder given twice is refused.
  """
  report = {}
  for folder, name in zip(folders, distinct_names(folders)):
    path = pathlib.Path(folder) / 'results.json'
    data = read_results(path)
    for suite, rows in data.items():
      for method, result in rows.items():
        rows_here = report.setdefault(suite, {})
        label = f'{method} ({name})' if method in rows_here else method
        if label in rows_here:
          raise ResultsError(f'{path}: {suite}/{method} cannot be told apart from a row of '
                             'another folder')
        rows_here[label] = rescored(result, f'{path}: {suite}/{method}')
  return report


def rescored(result, where: str) -> dict:
  """A row read back from results.json, scored again from its runs (what JSON dropped, such as
  NaN for an undefined metric, comes back)."""
  if not isinstance(result, dict) or 'runs' not in result:
    raise ResultsError(f'{where} holds no per-run counts (written before mvcoba-eval kept '
                       'them); evaluate it again')
  runs = result['runs']
  if not isinstance(runs, dict) or not runs or not all(
      isinstance(logs, list) and logs for logs in runs.values()):
    raise ResultsError(f'{where}.runs: expected each case\'s list of run logs')
  try:
    by_case = {name: [metrics.run_log(log, f'{where}.runs.{name}[{i}]')
                      for i, log in enumerate(logs)] for name, logs in runs.items()}
  except ValueError as e:
    raise ResultsError(str(e)) from None
  wall = result.get('wall_s')
  if wall is not None and (isinstance(wall, bool) or not isinstance(wall, (int, float))
                           or not 0 <= wall < WALL_LIMIT_S):
    raise ResultsError(f'{where}.wall_s: expected seconds in [0, {WALL_LIMIT_S:g}), got '
                       f'{str(wall)[:40]!r}')
  if 'settings' in result:
    fitting_settings(result['settings'], by_case, where)
  return scored(by_case, wall) | (
      {'settings': result['settings']} if 'settings' in result else {})


WALL_LIMIT_S = 10 ** 7  # seconds a row could take: about four months


def fitting_settings(settings, by_case: dict, where: str) -> None:
  """Raises ResultsError when a row's runs do not fit the settings it records: its cases, runs
  per case, action cap and the objects each case file lists (each that the settings hold), or
  its protocol is none that evaluation runs."""
  if not isinstance(settings, dict):
    raise ResultsError(f'{where}.settings: expected an object, got {str(settings)[:40]!r}')
  protocol = settings.get('protocol')  # None: written before evaluation recorded it (frozen)
  if protocol is not None and (not isinstance(protocol, str) or protocol not in PROTOCOLS):
    raise ResultsError(f'{where}.settings.protocol {str(protocol)[:40]!r}: one of '
                       f'{", ".join(PROTOCOLS)} expected')
  for key in ('cases', 'runs', 'max_actions'):
    if key not in settings or settings[key] is None:
      raise ResultsError(f'{where}.settings.{key}: missing; the row cannot be checked (evaluate '
                         'it again)')
  for key in ('runs', 'max_actions', 'seed', 'step'):  # a baseline row has no step (None)
    value = settings.get(key)
    if value is not None and (isinstance(value, bool) or not isinstance(value, int) or value < 0):
      raise ResultsError(f'{where}.settings.{key}: expected a count, got {str(value)[:40]!r}')
  cases, runs, cap = settings['cases'], settings['runs'], settings['max_actions']
  listed = settings.get('listed_objects')
  if not isinstance(cases, list) or not all(isinstance(c, str) for c in cases) or sorted(
      cases) != sorted(by_case):
    raise ResultsError(f'{where}.settings.cases: {str(cases)[:80]} are not the cases of its runs '
                       f'({", ".join(sorted(by_case))[:80]})')
  for name, logs in by_case.items():
    if len(logs) != runs:
      raise ResultsError(f'{where}.runs.{name}: {len(logs)} runs where its settings say {runs}')
    if any(log.actions > cap for log in logs):
      raise ResultsError(f'{where}.runs.{name}: a run took more actions than the cap of {cap} '
                         'its settings give')
    if (isinstance(listed, dict) and isinstance(listed.get(name), int)
        and any(log.objects > listed[name] for log in logs)):
      raise ResultsError(f'{where}.runs.{name}: a run began with more objects than the '
                         f'{listed[name]} its case file lists')
