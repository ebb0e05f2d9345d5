"""What a training run writes to its work directory: one JSON record per action (actions.jsonl),
their summary and the training curves (curves.png)."""
from __future__ import annotations

import json
import pathlib

import jax
import numpy as np
from jax.experimental import multihost_utils

from mvcoba_jax.learner import curves

PRIMITIVE_NAMES = ('push', 'grasp')


def action_records(log, first_action: int, viewpoints: int) -> list[dict]:
  """One JSON record per action of a (K, B) StepLog, numbered over all environments;
  `viewpoints`: camera views the method looked through for each action."""
  # With several processes each holds its own environments' part; gather the whole batch.
  log = multihost_utils.process_allgather(log, tiled=True) if jax.process_count() > 1 \
      else jax.tree.map(np.asarray, log)
  k, b = log.primitive.shape
  return [{'action': first_action + i * b + e, 'env': e,
           'primitive': PRIMITIVE_NAMES[int(log.primitive[i, e])],
           'grasp_success': bool(log.grasp_success[i, e]), 'changed': bool(log.changed[i, e]),
           'reward': float(log.reward[i, e]), 'done': bool(log.done[i, e]),
           'healthy': bool(log.healthy[i, e]), 'picked': int(log.picked[i, e]),
           'lost': int(log.lost[i, e]), 'explored': bool(log.explored[i, e]),
           'viewpoints': viewpoints}
          for i in range(k) for e in range(b)]


RECORD_FIELDS = {'action': int, 'primitive': str, 'grasp_success': bool}  # what summaries read


def read_records(path: pathlib.Path, below: int) -> list[dict]:
  """Action records before action `below` (a resumed run drops what came after its checkpoint).
  ValueError names the file and line of a record that is not one."""
  if not path.exists():
    return []
  records = []
  try:
    lines = path.read_text().splitlines()
  except (OSError, UnicodeDecodeError) as e:
    raise ValueError(f'{path}: cannot read it ({e})') from None
  for number, line in enumerate(lines, 1):
    try:
      record = json.loads(line)
    except (ValueError, RecursionError):
      raise ValueError(f'{path}:{number}: not a JSON action record') from None
    if not isinstance(record, dict) or not all(
        isinstance(record.get(k), t) and not (t is int and isinstance(record.get(k), bool))
        for k, t in RECORD_FIELDS.items()):
      raise ValueError(f'{path}:{number}: an action record needs '
                       f'{", ".join(f"{k} ({t.__name__})" for k, t in RECORD_FIELDS.items())}')
    if record['action'] < below:
      records.append(record)
  return records


def write_records(path: pathlib.Path, records: list[dict], mode: str) -> None:
  with path.open(mode) as f:
    f.writelines(json.dumps(r) + '\n' for r in records)


def summary(records: list[dict]) -> dict:
  grasps = [r for r in records if r['primitive'] == 'grasp']
  success = sum(r['grasp_success'] for r in grasps)
  return {'actions': len(records), 'grasp_attempts': len(grasps), 'grasp_successes': success,
          'grasp_success': success / max(len(grasps), 1),
          'grasps_per_action': success / max(len(records), 1),
          'pushes': len(records) - len(grasps)}


def plot_curves(workdir: pathlib.Path, records: list[dict], config) -> pathlib.Path:
  path = workdir / 'curves.png'
  curves.plot([r['primitive'] == 'grasp' for r in records],
              [r['grasp_success'] for r in records], config.train.curve_window, path,
              title=f'{config.network.method}, {config.num_envs} tabletops')
  return path


def plot_sweep(workdirs: list[pathlib.Path], window: int,
               folder: pathlib.Path) -> list[pathlib.Path]:
  """The sweep's curves: its runs grouped by method (`plot_groups`)."""
  groups = {}
  for workdir in workdirs:
    method = json.loads((workdir / 'config.json').read_text())['network']['method']
    records = read_records(workdir / 'actions.jsonl', below=10 ** 12)
    groups.setdefault(method, []).append(curves.on_actions(
        [r['primitive'] == 'grasp' for r in records], [r['grasp_success'] for r in records],
        window))
  return curves.plot_groups(groups, window, folder)

