"""The paper's online test protocol against the frozen one, network by network: for each method
and suite that both protocols of a reproduction finished, each metric's online score less the
frozen score of the same trained network, with Student's t interval over those per-seed
differences (paired: the seed's luck, shared by both protocols, cancels), and what the online
protocol's evaluation took against the frozen one's.

    python experiments/protocol_difference.py TABLES_DIR [--suites random ...] > difference.md
"""
from __future__ import annotations

import argparse
import pathlib
import sys

from mvcoba_jax.evaluation import intervals, paper, report

METRICS = (('grasp_success', 'grasp success'), ('completion', 'runs completed'),
           ('objects_picked', 'objects picked'), ('action_efficiency', 'action efficiency'))


def _by_network(rows: dict) -> dict:
  """(method, checkpoint, step) -> row: a trained network's row, whatever its label says."""
  out = {}
  for label, row in rows.items():
    settings = row.get('settings', {})
    out[(report.method_of(label), settings.get('checkpoint'), settings.get('step'))] = row
  return out


def differences(frozen: dict, online: dict) -> dict:
  """suite -> method -> {'seeds', 'time_ratio', metric: (mean, low, high) or None where a
  metric is undefined in some case}, over the networks both protocols evaluated on the suite and
  the cases both ran."""
  out = {}
  for suite in [s for s in frozen if s in online]:
    before, after = _by_network(frozen[suite]), _by_network(online[suite])
    paired = [key for key in before if key in after]
    for method in dict.fromkeys(key[0] for key in paired):
      keys = [key for key in paired if key[0] == method]
      cases = [c for c in before[keys[0]]['cases']
               if all(c in before[k]['cases'] and c in after[k]['cases'] for k in keys)]
      entry = {'seeds': len(keys), 'time_ratio': sum(after[k]['wall_s'] for k in keys)
               / sum(before[k]['wall_s'] for k in keys)}
      for metric, _ in METRICS:
        scores = lambda rows: [[rows[k]['cases'][c][metric] for c in cases] for k in keys]
        entry[metric] = intervals.paired(scores(after), scores(before))
      out.setdefault(suite, {})[method] = entry
  return out


def markdown(diffs: dict) -> str:
  """One table per suite: each method's online less frozen with its paired interval."""
  parts = []
  for suite, methods in diffs.items():
    lines = [f'### {suite}: online less frozen, mean [95% t interval over the seeds\' '
             'differences]', '',
             '| method | seeds | ' + ' | '.join(label for _, label in METRICS)
             + ' | evaluation time, online / frozen |',
             '|---|---|' + '---|' * (len(METRICS) + 1)]
    for method, e in methods.items():
      lines.append(f'| {paper.paper_name(method)} ({method}) | {e["seeds"]} | '
                   + ' | '.join(report.interval_cell(e[m]) for m, _ in METRICS)
                   + f' | {e["time_ratio"]:.2f} |')
    parts.append('\n'.join(lines))
  return '\n\n'.join(parts) + '\n'


def main() -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('tables', help="the reproduction's --out folder (online results in online/)")
  parser.add_argument('--suites', nargs='+', help='only these suites (default: every suite both '
                      'protocols hold)')
  args = parser.parse_args()
  tables = pathlib.Path(args.tables)
  try:
    frozen = report.read_results(tables / 'results.json', ' of the frozen protocol')
    online = report.read_results(tables / 'online' / 'results.json', ' of the online protocol')
  except report.ResultsError as e:
    sys.exit(f'protocol_difference: {e}')
  if args.suites:
    missing = [s for s in args.suites if s not in frozen or s not in online]
    if missing:
      sys.exit(f'protocol_difference: {", ".join(missing)}: not in both protocols\' results '
               f'(frozen: {", ".join(frozen)}; online: {", ".join(online)})')
    frozen = {suite: rows for suite, rows in frozen.items() if suite in args.suites}
  print(markdown(differences(frozen, online)))
  return 0


if __name__ == '__main__':
  sys.exit(main())
