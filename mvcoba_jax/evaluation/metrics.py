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
  for name in fields:
    value = data.get(name)
    if name == 'repeated_failures' and value is None:
      continue
    if name == 'completed':
      if not isinstance(value, bool):
        raise ValueError(f'{where}.completed: expected true or false, got {str(value)[:40]!r}')
    elif isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 2 ** 31:
      raise ValueError(f'{where}.{name}: expected a count, got {str(value)[:40]!r}')
  log = RunLog(**data)
  if not log.grasp_successes <= log.grasp_attempts <= log.actions:
    raise ValueError(f'{where}: grasp_successes {log.grasp_successes} <= grasp_attempts '
                     f'{log.grasp_attempts} <= actions {log.actions} does not hold')
  if log.picked and not log.grasp_successes:  # one grasp may lift several, none lifts none
    raise ValueError(f'{where}: picked {log.picked} objects without a successful grasp')
  if log.picked + log.lost > log.objects or log.completed and log.picked != log.objects:
    raise ValueError(f'{where}: picked {log.picked} and lost {log.lost} do not fit objects '
                     f'{log.objects} (completed: {log.completed})')
  return log


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
