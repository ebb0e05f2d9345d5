"""Evaluates trained policies (or a baseline) on test suites and prints the paper's tables.

  python eval.py --checkpoint runs/train [runs/vpg ...] [--suite random|ordered|occluded|isolated|vpg|all|PATH ...]
                 [--runs 5] [--max-actions 60] [--out eval_out] [--save-visuals]
  python eval.py --baseline heuristic --suite ordered        # no checkpoint needed
  python eval.py --compare runs/mvcoba runs/vpg ...          # same as several --checkpoint
  python eval.py --tables runs/eval-a runs/eval-b --out X    # one table from earlier --out folders

Every (case, run) pair of a suite runs in one jitted, vmapped call (cases padded to a common
object-slot pool). One table per suite and metric: methods as rows, cases as columns (paper
Tables 2-4); also written as JSON and Markdown to --out, rewritten as each method finishes, so a
killed evaluation keeps what it finished. --tables joins the results of evaluations run apart (in
parallel, or on other machines) into one table, with no compile. With --save-visuals, each run also
gets a PNG strip of its heightmaps and actions in --out/visuals/SUITE/METHOD/, beside losses.json:
every object that left the workspace, the action it left in and where it was when it began.
"""
from __future__ import annotations

import argparse
import collections
import dataclasses
import json
import math
import os
import pathlib
import sys
import time

import jax
from flax import nnx
from tqdm import tqdm

from envs.scenarios import ScenarioError, case_to_layout, read_case, stack_layouts
from envs.tabletop import Tabletop
from mvcoba_jax import config as config_lib
from mvcoba_jax import evaluation, metrics, networks, viz
from mvcoba_jax.export import ExportError, load
from mvcoba_jax.runtime import REPO_ROOT, enable_compilation_cache

SUITES = ('random', 'ordered', 'occluded', 'isolated', 'vpg')
VPG_CASES = REPO_ROOT.parent / 'shared' / 'vpg-test-cases'  # the 'vpg' suite's default folder
METRICS = (('grasp_success', 'grasp success (%)'), ('action_efficiency', 'action efficiency (%)'),
           ('completion', 'completion (%)'), ('objects_picked', 'objects picked (%)'),
           ('grasp_to_push', 'grasp-to-push ratio'))


class ResultsError(ValueError):
  """An earlier evaluation's results.json that --tables cannot use."""


def suite_files(names: list[str], vpg_dir: pathlib.Path) -> dict[str, list[pathlib.Path]]:
  """Suite name -> its case files; a PATH (file or folder) is a suite of its own."""
  if 'all' in names:
    names = [n for n in names if n != 'all'] + list(SUITES)
  out = {}
  for name in dict.fromkeys(names):
    if name in SUITES:
      folder = vpg_dir if name == 'vpg' else REPO_ROOT / 'suites' / name
      files = sorted(folder.glob('*.txt' if name == 'vpg' else '*.scn'))
    else:
      path = pathlib.Path(name)
      files = sorted(p for p in path.iterdir() if p.suffix in ('.scn', '.txt')) \
          if path.is_dir() else [path]
    if not files or not all(f.is_file() for f in files):
      raise ScenarioError(f'suite {name!r}: no case files found')
    out[name] = files
  return out


def pool_for(cases) -> tuple[tuple[str, int], ...]:
  """The smallest object-slot pool that holds every case of a suite."""
  need = collections.Counter()
  for case in cases:
    for shape, count in collections.Counter(o.shape for o in case.objects).items():
      need[shape] = max(need[shape], count)
  return tuple(sorted(need.items()))


def suite_config(config, pool):
  """`config` with the suite's pool and contact limits that grow with it.

  Random drops (`env.num_objects`) play no part in evaluation; they only have to fit the pool.
  """
  slots = sum(n for _, n in pool)
  scene = dataclasses.replace(config.scene, pool=pool,
                              max_contact_points=max(config.scene.max_contact_points, 10 * slots),
                              max_geom_pairs=max(config.scene.max_geom_pairs, 2 * slots))
  env = dataclasses.replace(config.env, num_objects=min(config.env.num_objects, slots))
  return dataclasses.replace(config, scene=scene, env=env)


def make_policy(method_source, config):
  """(name, policy factory for an env, views) of a checkpoint or a baseline."""
  if isinstance(method_source, str):  # a baseline
    policy = evaluation.heuristic_policy(config.env.num_rotations)
    return f'baseline:{method_source}', policy, (0, 1)
  config, model, step = method_source
  graphdef, params = nnx.split(model)
  method = config.network.method
  q_maps = lambda obs: nnx.merge(graphdef, params)(obs.color, obs.depth)
  return method, evaluation.greedy_policy(q_maps, method), networks.views_used(method)


def row_labels(directories: list[str], methods: list[str]) -> list[str]:
  """Table rows of the checkpoints: the method, with the run's folder when a method repeats."""
  repeated = {m for m in methods if methods.count(m) > 1}
  return [f'{m} ({pathlib.Path(d).name})' if m in repeated else m
          for d, m in zip(directories, methods)]


def json_safe(tree):
  """`tree` with NaN and infinities (undefined metrics) as null, which JSON can hold."""
  if isinstance(tree, dict):
    return {k: json_safe(v) for k, v in tree.items()}
  return None if isinstance(tree, float) and not math.isfinite(tree) else tree


def table(rows: dict[str, dict[str, dict]], key: str, label: str, cases: list[str]) -> str:
  """A Markdown table: methods as rows, cases and their mean as columns ('-': undefined/not run)."""
  head = f'| {label} | ' + ' | '.join(cases) + ' | mean |\n|---|' + '---|' * (len(cases) + 1)
  lines = [head]
  for method, result in rows.items():
    cells = [result['cases'].get(c, {}).get(key, math.nan) for c in cases] + [result['mean'][key]]
    lines.append(f'| {method} | ' + ' | '.join('-' if not math.isfinite(v) else f'{v:.1f}'
                                                for v in cells) + ' |')
  return '\n'.join(lines)


def suite_tables(suite: str, rows: dict[str, dict]) -> list[str]:
  """One Markdown table per metric of a suite; its columns are every case any method ran."""
  cases = list(dict.fromkeys(c for result in rows.values() for c in result['cases']))
  return [f'### {suite}: {label}\n\n' + table(rows, key, label, cases) for key, label in METRICS]


def scored(by_case: dict[str, list[metrics.RunLog]], wall_s: float) -> dict:
  """A method's row of a suite: metrics per case and their means, with the runs they came from."""
  per_case = {name: metrics.case_metrics(logs) for name, logs in by_case.items()}
  return {'cases': per_case, 'mean': metrics.suite_average(per_case), 'wall_s': wall_s,
          'runs': {name: [dataclasses.asdict(log) for log in logs]
                   for name, logs in by_case.items()}}


def loss_summary(lost: list[dict]) -> str:
  """One line on the objects that left the workspace (see `evaluation.losses`)."""
  grasps = [r for r in lost if r['primitive'] == 'grasp']
  return (f'{len(lost)} objects left the workspace ({len(grasps)} during grasps, '
          f'{len(lost) - len(grasps)} during pushes; '
          f'{sum(r["distance_to_gripper"] <= 0.03 for r in lost)} began within 3 cm of the '
          f'gripper\'s target, {sum(r["margin_to_border"] <= 0.03 for r in lost)} within 3 cm of '
          'the border): losses.json')


def write_report(report: dict, out: pathlib.Path) -> str:
  """Writes results.json and results.md (each replaced whole, never half written); the Markdown."""
  text = '\n\n'.join(t for suite, rows in report.items() for t in suite_tables(suite, rows)) + '\n'
  for name, content in (('results.json', json.dumps(json_safe(report), indent=1)),
                        ('results.md', text)):
    partial = out / f'.{name}.partial'
    partial.write_text(content)
    os.replace(partial, out / name)
  return text


def joined_report(folders: list[str]) -> dict:
  """The results.json of earlier evaluations as one report, scored again from their runs.

  A method met twice in a suite gets its --out folder's name after it.
  """
  report = {}
  for folder in folders:
    path = pathlib.Path(folder) / 'results.json'
    try:
      data = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as e:
      raise ResultsError(f'{path}: cannot read evaluation results ({e})') from None
    if not isinstance(data, dict) or not all(isinstance(rows, dict) for rows in data.values()):
      raise ResultsError(f'{path}: not the results of eval.py (suite -> method -> results)')
    for suite, rows in data.items():
      for method, result in rows.items():
        if not isinstance(result, dict) or 'runs' not in result:
          raise ResultsError(f'{path}: {suite}/{method} holds no per-run counts (written '
                              'before eval.py kept them); evaluate it again')
        try:
          by_case = {name: [metrics.RunLog(**log) for log in logs]
                     for name, logs in result['runs'].items()}
        except TypeError as e:
          raise ResultsError(f'{path}: {suite}/{method}: a run log is malformed ({e})') from None
        rows_here = report.setdefault(suite, {})
        label = f'{method} ({pathlib.Path(folder).name})' if method in rows_here else method
        rows_here[label] = scored(by_case, result.get('wall_s'))
  return report


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  config_lib.add_arguments(parser)
  parser.add_argument('--checkpoint', '--compare', nargs='+', default=[],
                      help='work directories of train.py runs, or folders written by '
                           'mvcoba_jax.export (e.g. pretrained/mvcoba)')
  parser.add_argument('--baseline', choices=('heuristic',),
                      help='a policy that needs no checkpoint')
  parser.add_argument('--tables', nargs='+', default=[], metavar='EVAL_DIR',
                      help='--out folders of earlier evaluations: print and write their joined '
                           'tables, evaluate nothing')
  parser.add_argument('--suite', nargs='+', default=['all'],
                      help=f'{", ".join(SUITES)}, all, or paths of case files/folders')
  parser.add_argument('--runs', type=int, default=5, help='runs per case')
  parser.add_argument('--max-actions', type=int, default=60, help='action cap per run')
  parser.add_argument('--vpg-dir', default=str(VPG_CASES))
  parser.add_argument('--out', default='eval_out', help='folder for JSON and Markdown tables')
  parser.add_argument('--seed', type=int, default=0)
  parser.add_argument('--save-visuals', action='store_true',
                      help='write a PNG strip of heightmaps and actions per run')
  args = parser.parse_args(argv)
  if args.tables:
    if args.checkpoint or args.baseline:
      parser.error('--tables joins earlier results; give it without --checkpoint or --baseline')
    try:
      report = joined_report(args.tables)
    except ResultsError as e:
      print(f'error: {e}', file=sys.stderr)
      return 2
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(write_report(report, out))
    print(f'wrote {out / "results.json"} and {out / "results.md"}')
    return 0
  if not args.checkpoint and not args.baseline:
    parser.error('give --checkpoint DIR ..., --baseline heuristic or --tables EVAL_DIR ...')
  try:  # everything that can be wrong with the input fails here, before any compile
    base = config_lib.from_arguments(args)
    suites = {name: [read_case(f) for f in files]
              for name, files in suite_files(args.suite, pathlib.Path(args.vpg_dir)).items()}
    sources = [load(d) for d in args.checkpoint] + ([args.baseline] if args.baseline else [])
    labels = row_labels(args.checkpoint, [s[0].network.method for s in sources
                                          if not isinstance(s, str)])
  except (config_lib.ConfigError, ScenarioError, ExportError) as e:
    print(f'error: {e}', file=sys.stderr)
    return 2
  enable_compilation_cache()
  out = pathlib.Path(args.out)
  out.mkdir(parents=True, exist_ok=True)
  report = {}
  for suite, cases in suites.items():
    names = [c.name for c in cases]
    rows = {}
    for i, source in enumerate(sources):
      config = base if isinstance(source, str) else source[0]
      env = Tabletop(suite_config(config, pool_for(cases)))
      method, policy, views = make_policy(source, env.config)
      method = labels[i] if i < len(labels) else method
      layouts = stack_layouts([case_to_layout(c, env) for c in cases for _ in range(args.runs)])
      keys = jax.random.split(jax.random.PRNGKey(args.seed), len(cases) * args.runs)
      print(f'{suite}: {method}, {len(cases)} cases x {args.runs} runs, up to '
            f'{args.max_actions} actions each; compiling and running...', flush=True)
      start = time.perf_counter()
      with tqdm(total=args.max_actions, unit='action', desc=f'  {suite}') as bar:
        def progress(done, finished, bar=bar, n=len(layouts.in_play)):
          bar.set_postfix_str(f'{int(finished)}/{n} runs finished', refresh=False)
          bar.update(int(done) - bar.n)
        runs = jax.jit(lambda l, k: evaluation.evaluate(
            env, policy, views, l, k, args.max_actions, record=args.save_visuals,
            progress=progress))(layouts, keys)
        logs = evaluation.run_logs(runs)
      if args.save_visuals:
        folder = out / 'visuals' / pathlib.Path(suite).name / method.replace(':', '_')
        run_names = [f'{n}_run{r}' for n in names for r in range(args.runs)]
        viz.write_run_strips(jax.device_get(runs.trace), run_names, folder, env.config)
        lost = evaluation.losses(runs.trace, run_names, env.config)
        (folder / 'losses.json').write_text(json.dumps(lost, indent=1))
        print(f'  visuals in {folder}; {loss_summary(lost)}', flush=True)
      by_case = {name: logs[i * args.runs:(i + 1) * args.runs] for i, name in enumerate(names)}
      rows[method] = scored(by_case, time.perf_counter() - start)
      report[suite] = rows
      write_report(report, out)
      print(f'  done in {rows[method]["wall_s"]:.0f} s', flush=True)
    for text in suite_tables(suite, rows):
      print('\n' + text)
  print(f'\nwrote {out / "results.json"} and {out / "results.md"}')
  return 0


if __name__ == '__main__':
  sys.exit(main())
