"""The paper's evaluation metrics (docs/design.md) from per-run counts.

Per run: actions executed, grasp attempts, successful grasps, objects in the case, objects
picked, and whether the run completed (every object picked without more than the allowed
consecutive failures). Rates are percentages, as in the paper's tables.
"""
from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class RunLog:
  actions: int
  grasp_attempts: int
  grasp_successes: int
  objects: int
  picked: int
  lost: int
  completed: bool
  # Actions that repeated a failed action of the run exactly (primitive, rotation and cell) with
  # nothing changed since; None in results written before it was counted.
  repeated_failures: int | None = None
  # Per shape (`SHAPE_COUNTS`; NO_OBJECT for actions at none): what `shape_counts` gives; None
  # in results written before it was counted.
  shapes: dict[str, dict[str, int]] | None = None


# A shape's counts in a run: objects in play at the start, objects picked, grasps aimed at one
# (the object lifted, else the one under the grasp's point), those that lifted something, and
# pushes that moved one farthest (`evaluation.runner`).
SHAPE_COUNTS = ('objects', 'picked', 'grasps', 'lifted', 'pushes')
NO_OBJECT = '(no object)'


def shape_counts(by_slot: list[list[int]], slot_shapes: tuple[str, ...]) -> dict:
  """{shape: {count: n}} of one run from its per-slot counts (M + 1 rows, the last for actions
  at no object), shapes with nothing counted left out."""
  out = {}
  for name, row in zip(list(slot_shapes) + [NO_OBJECT], by_slot):
    totals = out.setdefault(name, dict.fromkeys(SHAPE_COUNTS, 0))
    for key, n in zip(SHAPE_COUNTS, row):
      totals[key] += int(n)
  return {name: c for name, c in out.items() if any(c.values())}


def run_log(data, where: str) -> RunLog:
  """A RunLog from its JSON object, checked: counts are non-negative integers that fit each
  other (successes <= attempts <= actions, picked + lost <= objects); ValueError names the
  field otherwise."""
  if not isinstance(data, dict):
    raise ValueError(f'{where}: a run log is an object of counts, got {str(data)[:40]!r}')
  fields = {f.name for f in dataclasses.fields(RunLog)}
  unknown = sorted(set(data) - fields)
  if unknown:
    raise ValueError(f'{where}: unknown fields {", ".join(unknown)[:80]}')
  for name in fields - {'shapes'}:
    value = data.get(name)
    if name == 'repeated_failures' and value is None:
      continue
    if name == 'completed':
      if not isinstance(value, bool):
        raise ValueError(f'{where}.completed: expected true or false, got {str(value)[:40]!r}')
    elif isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 2 ** 31:
      raise ValueError(f'{where}.{name}: expected a count, got {str(value)[:40]!r}')
  log = RunLog(**data)
  if log.shapes is not None:
    _check_shapes(log, where)
  if not log.grasp_successes <= log.grasp_attempts <= log.actions:
    raise ValueError(f'{where}: grasp_successes {log.grasp_successes} <= grasp_attempts '
                     f'{log.grasp_attempts} <= actions {log.actions} does not hold')
  if log.picked and not log.grasp_successes:  # one grasp may lift several, none lifts none
    raise ValueError(f'{where}: picked {log.picked} objects without a successful grasp')
  if log.picked + log.lost > log.objects or log.completed and log.picked != log.objects:
    raise ValueError(f'{where}: picked {log.picked} and lost {log.lost} do not fit objects '
                     f'{log.objects} (completed: {log.completed})')
  return log


def _check_shapes(log: RunLog, where: str) -> None:
  """A run's per-shape counts: counts that fit each other and sum to the run's own."""
  if not isinstance(log.shapes, dict):
    raise ValueError(f'{where}.shapes: expected an object of shapes, got {str(log.shapes)[:40]!r}')
  for name, counts in log.shapes.items():
    at = f'{where}.shapes[{name[:60]!r}]'
    if not isinstance(counts, dict) or set(counts) != set(SHAPE_COUNTS):
      raise ValueError(f'{at}: expected the counts {", ".join(SHAPE_COUNTS)}')
    if any(isinstance(n, bool) or not isinstance(n, int) or not 0 <= n < 2 ** 31
           for n in counts.values()):
      raise ValueError(f'{at}: expected counts, got {str(counts)[:60]}')
    if counts['lifted'] > counts['grasps'] or counts['picked'] > counts['objects']:
      raise ValueError(f'{at}: lifted <= grasps and picked <= objects do not hold')
  total = lambda key: sum(c[key] for c in log.shapes.values())
  for key, whole in (('objects', log.objects), ('picked', log.picked),
                     ('grasps', log.grasp_attempts), ('lifted', log.grasp_successes),
                     ('pushes', log.actions - log.grasp_attempts)):
    if total(key) != whole:
      raise ValueError(f'{where}.shapes: {key} sum to {total(key)}, the run counts {whole}')


def shape_metrics(runs: list[RunLog]) -> dict | None:
  """Per shape, over `runs`: objects in play at the start and the share picked, grasps aimed at
  it and the share that lifted something, pushes that moved it most; None when a run lacks the
  counts (results written before they were kept)."""
  if not runs or any(r.shapes is None for r in runs):
    return None
  sums = {}
  for r in runs:
    for name, counts in r.shapes.items():
      totals = sums.setdefault(name, dict.fromkeys(SHAPE_COUNTS, 0))
      for key in SHAPE_COUNTS:
        totals[key] += counts[key]
  rate = lambda a, b: 100.0 * a / b if b else float('nan')
  return {name: {'objects': c['objects'], 'objects_picked': rate(c['picked'], c['objects']),
                 'grasps': c['grasps'], 'grasp_success': rate(c['lifted'], c['grasps']),
                 'pushes': c['pushes']}
          for name, c in sorted(sums.items(), key=lambda kv: (kv[0] == NO_OBJECT, kv[0]))}


def case_metrics(runs: list[RunLog]) -> dict:
  """Metrics of the runs of one case.

  grasp success = successful grasps / grasp attempts (over all runs);
  action efficiency = objects in the case / actions, over completed runs (NaN if none completed);
  completion = share of runs that picked every object;
  objects picked = objects picked / objects in the case, over all runs: the paper's text defines
    its completion rate this way (section 5.4; its per-case figures such as 81.2 and 82.5 are no
    share of 5 runs), so this is the column to hold against the paper's completion;
  grasp-to-push ratio = grasp attempts / pushes (inf when nothing was pushed);
  grasp success and action efficiency per completed run: the paper's averages (the authors'
    evaluate.py): each completed run's own rate, averaged over the completed runs (NaN if none);
  repeated failures = actions that repeated a failed action exactly, per run (NaN where not
    counted).
  """
  attempts = sum(r.grasp_attempts for r in runs)
  successes = sum(r.grasp_successes for r in runs)
  completed = [r for r in runs if r.completed]
  actions = sum(r.actions for r in runs)
  pushes = actions - attempts
  return {
      'grasp_success': 100.0 * successes / attempts if attempts else float('nan'),
      'action_efficiency': (100.0 * sum(r.objects for r in completed)
                            / sum(r.actions for r in completed)) if completed else float('nan'),
      'completion': 100.0 * len(completed) / len(runs),
      'objects_picked': (100.0 * sum(r.picked for r in runs) / sum(r.objects for r in runs)
                         if any(r.objects for r in runs) else float('nan')),
      'grasp_to_push': attempts / pushes if pushes else float('inf'),
      'grasp_success_per_run': (100.0 * float(np.mean([r.grasp_successes / r.grasp_attempts
                                                      for r in completed]))
                                if completed and all(r.grasp_attempts for r in completed)
                                else float('nan')),
      'action_efficiency_per_run': (100.0 * float(np.mean([r.objects / r.actions
                                                          for r in completed]))
                                    if completed and all(r.actions for r in completed)
                                    else float('nan')),
      'repeated_failures': (float(np.mean([r.repeated_failures for r in runs]))
                            if runs and all(r.repeated_failures is not None for r in runs)
                            else float('nan')),
      'runs': len(runs), 'actions': actions,
  }


def suite_average(per_case: dict[str, dict]) -> dict:
  """Mean of each metric over the cases (NaN cases are skipped, as a missing table cell)."""
  keys = ('grasp_success', 'action_efficiency', 'completion', 'objects_picked', 'grasp_to_push',
          'grasp_success_per_run', 'action_efficiency_per_run', 'repeated_failures')
  out = {}
  for k in keys:
    values = np.array([m.get(k, np.nan) for m in per_case.values()], float)
    finite = values[np.isfinite(values)]
    out[k] = float(finite.mean()) if finite.size else float('nan')
  return out
