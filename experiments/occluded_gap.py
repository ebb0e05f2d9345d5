"""Where MV-COBA loses grasps under held-out occluders: the shipped occluded cases evaluated again
with every occluder where the test puts it, moved into the region training draws from, moved down
to the validation cases' heights, and taken away, the objects unchanged. Each moved occluder keeps
its along and side coordinates (`sim/occluders.py`; the three regions share them): `training`
raises it 8 cm and turns it 25 degrees further from facing its camera (test heights 0.45-0.50 m
and turns 0-8 degrees land at 0.53-0.58 m and 25-33 degrees, inside training's region),
`validation` lowers it 8 cm (0.37-0.42 m, the validation region). Writes each condition's cases,
how many objects each camera sees in them (`suites.visibility`), the evaluation of the policies
on all four (`api.evaluate`, frozen, resumable), and a table with intervals over training seeds.

  python experiments/occluded_gap.py --checkpoints runs/mvcoba-s0 ... runs/mvcoba-s4 --out OUT \
    [--conditions test training validation none]
"""
from __future__ import annotations

import argparse
import json
import math
import pathlib
import sys

import numpy as np

from mvcoba_jax import api, runtime
from mvcoba_jax.config import Error, resolve
from mvcoba_jax.evaluation import intervals, report
from mvcoba_jax.sim.scenarios import read_case
from mvcoba_jax.suites import SUITES_DIR
from mvcoba_jax.suites.visibility import visibility

# condition -> (height shift in m, extra turn away from facing the camera in degrees), or None:
# no occluders.
CONDITIONS = {'test': (0.0, 0.0), 'training': (0.08, 25.0), 'validation': (-0.08, 0.0),
              'none': None}
METRICS = (('grasp_success', 'grasp success'), ('objects_picked', 'objects picked'),
           ('completion', 'runs completed'))


def facing_turn(x: float, y: float, yaw_deg: float, cameras_xy) -> float:
  """The occluder's turn (deg, in (-90, 90]) from facing the camera nearest it, the one it hides;
  a box is the same under a half turn."""
  camera = min(cameras_xy, key=lambda c: math.hypot(c[0] - x, c[1] - y))
  turn = yaw_deg - math.degrees(math.atan2(camera[1], camera[0]))
  return -((-turn + 90.0) % 180.0 - 90.0)


def moved(text: str, height: float, turn: float, cameras_xy) -> str:
  """A case file's text with every occluder line raised by `height` and turned `turn` degrees
  further from facing its camera (either way, away from facing); other lines as they were."""
  lines = []
  for line in text.splitlines():
    fields = line.split()
    if fields and fields[0] == 'occluder':
      slot, x, y, z, yaw = fields[1], *map(float, fields[2:6])
      away = math.copysign(turn, facing_turn(x, y, yaw, cameras_xy) or 1.0)
      line = f'occluder {slot} {x:.5f} {y:.5f} {z + height:.5f} {yaw + away:.3f}'
    lines.append(line)
  return '\n'.join(lines) + '\n'


def without_occluders(text: str) -> str:
  return '\n'.join(line for line in text.splitlines()
                   if not line.split()[:1] == ['occluder']) + '\n'


def write_conditions(out: pathlib.Path, cameras_xy, names=tuple(CONDITIONS),
                     source=SUITES_DIR / 'dev-occluded') -> dict:
  """Condition -> the folder of its case files under `out`, made from `source`'s cases, for
  the conditions `names`."""
  folders = {}
  for name in names:
    change = CONDITIONS[name]
    folder = out / 'cases' / name
    folder.mkdir(parents=True, exist_ok=True)
    for path in sorted(source.glob('*.scn')):
      text = path.read_text()
      text = without_occluders(text) if change is None else moved(text, *change, cameras_xy)
      (folder / path.name).write_text(text)
    folders[name] = folder
  return folders


def seen(folder: pathlib.Path, config) -> dict:
  """Objects of the condition's cases, and of them those seen by one camera only and by none."""
  rows = visibility([read_case(f) for f in sorted(folder.glob('*.scn'))], config)
  count = lambda key: sum(len(r[key]) for r in rows)
  return {'objects': sum(len(r['objects']) for r in rows), 'one_camera_only':
          count('seen_by_one_only'), 'no_camera': count('seen_by_none'),
          'per_case': {r['case']: {'one_camera_only': len(r['seen_by_one_only']),
                                   'no_camera': len(r['seen_by_none'])} for r in rows}}


def interval_rows(results: dict, folders: dict, sights: dict, cases: list[str]) -> list[str]:
  """Table rows over `cases`: per condition, each metric's mean [95% t interval over seeds], the
  grasp success less that of the same seed with no occluders (paired: the interval is over each
  seed's difference) and the per-seed grasp success."""
  lines = []
  bare = results[str(folders['none'])]
  for name, folder in folders.items():
    rows = {label: {**row, 'cases': {c: row['cases'][c] for c in cases}}
            for label, row in results[str(folder)].items()}
    hidden = [sum(sights[name]['per_case'][c][k] for c in cases)
              for k in ('one_camera_only', 'no_camera')]
    groups = report.training_groups(rows)
    for group, entry in report.seed_intervals(rows).items():
      labels = groups[group]
      scores = lambda of: [[of[label]['cases'][c]['grasp_success'] for c in cases]
                           for label in labels]
      cost = intervals.paired(scores(rows), scores(bare))
      lines.append(f'| {name} ({group}) | {hidden[0]} / {hidden[1]} | {entry["seeds"]} | '
                   + ' | '.join(report.interval_cell(entry[k]) for k, _ in METRICS)
                   + f' | {report.interval_cell(cost)}'
                   + f' | {report.per_seed_cell(entry["per_seed"]["grasp_success"])} |')
  return lines


def table(results: dict, folders: dict, sights: dict) -> str:
  """Markdown: per condition, the metrics with intervals over seeds on every case, then on the
  cases where every condition leaves each object seen by some camera, then grasp success per
  case (mean over seeds)."""
  head = ('| occluders | objects seen by one camera only / none | seeds | '
          + ' | '.join(label for _, label in METRICS)
          + " | grasp success less none's, paired by seed | grasp success per seed |\n"
          + '|---|---|---|' + '---|' * (len(METRICS) + 2))
  cases = sorted(sights['none']['per_case'])
  seen_by_some = [c for c in cases if all(s['per_case'][c]['no_camera'] == 0
                                          for s in sights.values())]
  per_case = {name: {c: np.mean([r['cases'][c]['grasp_success']
                                 for r in results[str(folder)].values()]) for c in cases}
              for name, folder in folders.items()}
  return '\n'.join(
      [f'Every case ({len(cases)}):', '', head] + interval_rows(results, folders, sights, cases)
      + ['', f'The cases where every condition leaves each object seen by some camera '
             f'({", ".join(seen_by_some)}):', '', head]
      + interval_rows(results, folders, sights, seen_by_some)
      + ['', '| grasp success, mean over seeds | ' + ' | '.join(cases) + ' |',
         '|---|' + '---|' * len(cases)]
      + [f'| {name} | ' + ' | '.join(f'{v[c]:.1f}' for c in cases) + ' |'
         for name, v in per_case.items()]) + '\n'


def main() -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--checkpoints', nargs='+', required=True,
                      help='work directories (or exports) of one method, one per training seed')
  parser.add_argument('--out', required=True)
  parser.add_argument('--runs', type=int, default=5, help='runs per case')
  parser.add_argument('--conditions', nargs='+', choices=CONDITIONS, default=list(CONDITIONS),
                      help='the conditions to evaluate (none, the reference, always)')
  args = parser.parse_args()
  runtime.setup()
  out = pathlib.Path(args.out)
  config = resolve('default')
  cameras_xy = [c.pos[:2] for c in config.scene.cameras]
  folders = write_conditions(out, cameras_xy, dict.fromkeys(args.conditions + ['none']))
  sights = {name: seen(folder, config) for name, folder in folders.items()}
  (out / 'visibility.json').write_text(json.dumps(sights, indent=1))
  try:
    results = api.evaluate(args.checkpoints, [str(f) for f in folders.values()], runs=args.runs,
                           out=out / 'eval', resume=True)
  except Error as e:
    sys.exit(f'occluded_gap: {e}')
  (out / 'table.md').write_text(table(results, folders, sights))
  print((out / 'table.md').read_text())
  return 0


if __name__ == '__main__':
  sys.exit(main())
