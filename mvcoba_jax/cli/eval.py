"""Evaluates trained policies (or a baseline) on test suites and prints the paper's tables.

  mvcoba-eval --checkpoint runs/train [runs/vpg ...] [--suite random|ordered|occluded|isolated|vpg|all|PATH ...]
              [--runs 5] [--max-actions 60] [--out eval_out] [--resume] [--online|--no-repeat]
              [--save-visuals] [--video]
  mvcoba-eval --baseline heuristic --suite ordered        # no checkpoint needed
  mvcoba-eval --compare runs/mvcoba runs/vpg ...          # same as several --checkpoint
  mvcoba-eval --tables runs/eval-a runs/eval-b --out X    # one table from earlier --out folders

Every (case, run) pair of a suite runs in lockstep in one compiled loop (cases padded to a
common object-slot pool; the runs still going move to smaller batches as others finish). One
table per suite and metric: methods as rows, cases as columns (paper Tables 2-4); also written as
JSON and Markdown to --out, rewritten as each method finishes, so a killed evaluation keeps what
it finished, and --resume evaluates only what it did not (a row is kept when its checkpoint,
parameters, cases and settings are the same). --tables joins the results of evaluations run
apart (in parallel, or on other machines) into one table, with no compile. With
--save-visuals, each run also gets a PNG strip of its heightmaps and actions in
--out/visuals/SUITE/METHOD/, beside losses.json: every object that left the workspace, the action
it left in and where it was when it began. With --video, each run gets an MP4 of the scene and
the gripper in --out/videos/SUITE/METHOD/.
"""
from __future__ import annotations

import argparse
import json
import pathlib
import sys
import time

import jax
from tqdm import tqdm

from mvcoba_jax import config as config_lib
from mvcoba_jax import evaluation, folders, paper, runtime, video, viz
from mvcoba_jax import report as report_lib
from mvcoba_jax.cli import fail
from mvcoba_jax.policy import PolicyError, fingerprint, load
from mvcoba_jax.sim.scenarios import (
  ScenarioError,
  case_to_layout,
  read_case,
  stack_layouts,
)
from mvcoba_jax.sim.shapes import BLOCK_TABLES
from mvcoba_jax.sim.tabletop import Tabletop
from mvcoba_jax.suites import SUITES, suite_files

# What an evaluation writes to --out: refused to a new one without --resume or --overwrite.
RESULT_FILES = ('results.json', 'results.md', 'comparison.md', 'visuals', 'videos')


class UsageError(ValueError):
  """Arguments that ask for more work than an evaluation can hold."""


MAX_ACTIONS_LIMIT = 10_000  # per run: counters and traces grow with it
MAX_BATCH_RUNS = 4096  # cases x runs of a suite step in one batch, each a whole tabletop


def check_work(runs: int, max_actions: int, suites: dict[str, list]) -> None:
  """Refuses --runs and --max-actions whose work no evaluation could finish or hold, naming the
  limit, before anything is loaded or compiled."""
  if not 1 <= max_actions <= MAX_ACTIONS_LIMIT:
    raise UsageError(f'--max-actions {max_actions}: allowed range [1, {MAX_ACTIONS_LIMIT}]')
  for name, files in suites.items():
    if runs < 1 or runs * len(files) > MAX_BATCH_RUNS:
      raise UsageError(f'--runs {runs} x {len(files)} cases of suite {name}: between 1 and '
                       f'{MAX_BATCH_RUNS} runs of a suite step in one batch')


def block_tables(given: list[str], suites: list[str]) -> dict[str, str]:
  """--blocks as suite ('' for every suite) -> block table, each suite named once and among
  the evaluated ones, each table a known one; UsageError otherwise."""
  tables = {}
  for item in given:
    suite, _, table = item.rpartition('=')
    if table not in BLOCK_TABLES or '=' in suite:
      raise UsageError(f'--blocks {item[:80]!r}: expected [SUITE=]TABLE with TABLE one of '
                       f'{", ".join(BLOCK_TABLES)}')
    if suite and suite not in suites:
      raise UsageError(f'--blocks {item[:80]!r}: {suite[:60]!r} is not an evaluated suite '
                       f'({", ".join(suites)[:120]})')
    if suite in tables:
      raise UsageError(f'--blocks names {suite[:60] or "every suite"!r} twice')
    tables[suite] = table
  return tables


def _output_folder(path: str, keep: bool, overwrite: bool) -> pathlib.Path | None:
  """The --out folder, created and locked; None (and the error printed) when it cannot be, is
  in use, or holds results this invocation would replace unasked."""
  try:
    return folders.claim(path, RESULT_FILES, keep=keep, overwrite=overwrite)
  except folders.FolderError as e:
    print(f'error: --out {e}', file=sys.stderr)
    return None


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  config_lib.add_arguments(parser)
  parser.add_argument('--checkpoint', '--compare', nargs='+', default=[],
                      help='work directories of mvcoba-train runs, or folders written by '
                           'mvcoba-export (e.g. pretrained/mvcoba)')
  parser.add_argument('--baseline', choices=('heuristic',),
                      help='a policy that needs no checkpoint')
  parser.add_argument('--tables', nargs='+', default=[], metavar='EVAL_DIR',
                      help='--out folders of earlier evaluations: print and write their joined '
                           'tables, evaluate nothing')
  parser.add_argument('--suite', nargs='+', default=['all'],
                      help=f'{", ".join(SUITES)}, all, or paths of case files/folders')
  parser.add_argument('--runs', type=int, default=5, help='runs per case')
  parser.add_argument('--max-actions', type=int, default=60, help='action cap per run')
  parser.add_argument('--out', default='eval_out', help='folder for JSON and Markdown tables')
  parser.add_argument('--seed', type=int, default=0)
  parser.add_argument('--resume', action='store_true',
                      help="keep the rows of --out's results.json evaluated with the same "
                           'checkpoint, cases and settings; evaluate the rest (videos and '
                           'strips are written for those only)')
  parser.add_argument('--online', action='store_true',
                      help='the test protocol of VPG and the MV-COBA authors: every run starts '
                           'from the trained weights and takes one SGD step after each of its '
                           'actions (rows labelled [online]); default: the trained network, '
                           'frozen')
  parser.add_argument('--no-repeat', action='store_true',
                      help='frozen, but a run never takes a failed action of its own again while '
                           'nothing has changed (its next best one instead; rows labelled '
                           '[no-repeat]): beyond the paper')
  parser.add_argument('--overwrite', action='store_true',
                      help="replace --out's earlier results (refused otherwise)")
  parser.add_argument('--save-visuals', action='store_true',
                      help='write a PNG strip of heightmaps and actions per run')
  parser.add_argument('--video', action='store_true',
                      help=f'write an MP4 per run: the scene and the gripper, '
                           f'{video.FRAMES_PER_PRIMITIVE} frames per primitive')
  parser.add_argument('--blocks', nargs='+', default=[], metavar='[SUITE=]TABLE',
                      help='block table for VPG-format (.txt) case files: vpg (default), mvcoba '
                           '(the MV-COBA authors\' block set); SUITE=TABLE for one suite only')
  parser.add_argument('--allow-bad-cases', '--allow-overlaps', action='store_true',
                      help='evaluate cases that fail the load check (refused otherwise): objects '
                           'that interpenetrate as placed, leave the workspace as the case '
                           'settles, or move more than 1 cm from where the file puts them on '
                           'the table')
  args = parser.parse_args(argv)
  if args.tables:
    if args.checkpoint or args.baseline:
      parser.error('--tables joins earlier results; give it without --checkpoint or --baseline')
    try:
      folders.check(args.out, RESULT_FILES, overwrite=args.overwrite)
      report = report_lib.joined_report(args.tables)
    except (report_lib.ResultsError, folders.FolderError) as e:
      return fail(e)
    out = _output_folder(args.out, keep=False, overwrite=args.overwrite)
    if out is None:
      return 2
    try:
      print(report_lib.write_report(report, out))
      report_lib.write_whole(out / 'comparison.md', paper.comparisons(report) + '\n')
    except report_lib.ResultsError as e:
      return fail(e)
    print(f'wrote {out / "results.json"}, {out / "results.md"} and {out / "comparison.md"} '
          '(beside the paper)')
    return 0
  if args.resume and args.overwrite:
    parser.error('--resume keeps the rows of --out and --overwrite replaces them: give one')
  if not args.checkpoint and not args.baseline:
    parser.error('give --checkpoint DIR ..., --baseline heuristic or --tables EVAL_DIR ...')
  if (args.online or args.no_repeat) and args.baseline:
    parser.error('--online and --no-repeat change how a trained network acts; --baseline has '
                 'none')
  if args.online and args.no_repeat:
    parser.error('--no-repeat is a frozen protocol; give it or --online')
  protocol = 'online' if args.online else 'no-repeat' if args.no_repeat else 'frozen'
  try:  # everything that can be wrong with the input fails here, before any compile
    folders.check(args.out, RESULT_FILES, keep=args.resume, overwrite=args.overwrite)
    check_work(args.runs, args.max_actions, suite_files(args.suite))
    base = config_lib.from_arguments(args)
    bounds = base.scene.workspace_half, base.scene.workspace_top
    files_of = suite_files(args.suite)
    tables = block_tables(args.blocks, list(files_of))
    suites = {name: [read_case(f, *bounds, blocks=tables.get(name, tables.get('', 'vpg')))
                     for f in files]
              for name, files in files_of.items()}
    bad = [m for cases in suites.values() for m in evaluation.case_problems(cases, base)]
    loaded = [load(path) for path in args.checkpoint]
    trained = [(config_lib.trained_as(c), c.seed) for c, _, _ in loaded] + [(None, None)]
    sources = [(config_lib.evaluated(c, args.overrides), model, step) for c, model, step in loaded]
    sources += [args.baseline] if args.baseline else []
    source_names = [evaluation.source_name(s) for s in sources]
    labels = (report_lib.row_labels(args.checkpoint, source_names[:len(args.checkpoint)])
              + source_names[len(args.checkpoint):])
    if protocol != 'frozen':
      labels = [f'{label} [{protocol}]' for label in labels]
    settings = {(suite, label): {
        'checkpoint': path, 'step': None if isinstance(source, str) else source[2],
        'params': None if isinstance(source, str) else fingerprint(source[1]),
        'cases': [c.name for c in cases], 'runs': args.runs, 'max_actions': args.max_actions,
        'seed': args.seed, 'set': args.overrides, 'training': training[0],
        'training_seed': training[1], 'protocol': protocol}
        for suite, cases in suites.items()
        for label, source, path, training in zip(labels, sources, args.checkpoint + [None],
                                                 trained)}
    report = report_lib.kept_rows(pathlib.Path(args.out), settings) if args.resume else {}
  except (config_lib.ConfigError, ScenarioError, PolicyError, report_lib.ResultsError,
          UsageError, folders.FolderError) as e:
    return fail(e)
  if bad and not args.allow_bad_cases:
    return fail('\n  '.join(bad) + '\n(--allow-bad-cases evaluates them anyway)')
  for suite, cases in suites.items():
    parked = sum(len(c.parked_lines) for c in cases)
    if parked:
      print(f'{suite}: {parked} lines of its VPG files lie outside VPG\'s workspace (objects VPG '
            'parked) and are not in play')
  out = _output_folder(args.out, keep=args.resume, overwrite=args.overwrite)
  if out is None:
    return 2
  bad_outputs = [name for name, wanted in (('visuals', args.save_visuals), ('videos', args.video))
                 if wanted and (out / name).exists() and not (out / name).is_dir()]
  if bad_outputs:
    print(f'error: --out {out}: {", ".join(bad_outputs)} is a file, where the runs\' pictures '
          'go', file=sys.stderr)
    return 2
  runtime.setup()
  try:
    evaluate_suites(args, suites, dict(zip(labels, sources)), base, settings, report, out)
  except report_lib.ResultsError as e:
    return fail(e)
  print(f'\nwrote {out / "results.json"} and {out / "results.md"}')
  return 0


def evaluate_suites(args, suites: dict, policies: dict, base, settings: dict, report: dict,
                    out: pathlib.Path) -> None:
  """Evaluates every policy (label -> source) on every suite that `report` does not hold yet,
  rewriting --out's results after each row; prints each suite's tables."""
  for suite, cases in suites.items():
    names = [c.name for c in cases]
    rows = report.setdefault(suite, {})
    for label, source in policies.items():
      if label in rows:
        print(f'{suite}: {label}: kept from {out / "results.json"}', flush=True)
        continue
      config = base if isinstance(source, str) else source[0]
      env = Tabletop(evaluation.suite_config(config, evaluation.pool_for(cases)),
                     frames=video.FRAMES_PER_PRIMITIVE if args.video else 0)
      policy, views = evaluation.make_policy(source, env.config, args.online, args.no_repeat)
      layouts = stack_layouts([case_to_layout(c, env) for c in cases for _ in range(args.runs)])
      keys = jax.random.split(jax.random.PRNGKey(args.seed), len(cases) * args.runs)
      print(f'{suite}: {label}, {len(cases)} cases x {args.runs} runs, up to '
            f'{args.max_actions} actions each; compiling and running...', flush=True)
      start = time.perf_counter()
      with tqdm(total=args.max_actions, unit='action', desc=f'  {suite}') as bar:
        def progress(done, finished, bar=bar, n=len(layouts.in_play)):
          bar.set_postfix_str(f'{int(finished)}/{n} runs finished', refresh=False)
          bar.update(int(done) - bar.n)
        runs = evaluation.evaluate(env, policy, views, layouts, keys, args.max_actions,
                                   record=args.save_visuals or args.video, progress=progress)
        logs = evaluation.run_logs(runs)
      run_names = [f'{n}_run{r}' for n in names for r in range(args.runs)]
      where = pathlib.Path(pathlib.Path(suite).name) / label.replace(':', '_')
      if args.video:
        paths = video.write_run_videos(jax.device_get(runs.trace), run_names,
                                       out / 'videos' / where, env)
        print(f'  {len(paths)} videos in {out / "videos" / where}', flush=True)
      if args.save_visuals:
        folder = out / 'visuals' / where
        viz.write_run_strips(jax.device_get(runs.trace), run_names, folder, env.config)
        lost = evaluation.losses(runs.trace, run_names, env.config)
        (folder / 'losses.json').write_text(json.dumps(lost, indent=1))
        print(f'  visuals in {folder}; {report_lib.loss_summary(lost)}', flush=True)
      by_case = {name: logs[i * args.runs:(i + 1) * args.runs] for i, name in enumerate(names)}
      uneven = report_lib.uneven_starts(by_case)
      if uneven:
        print(f'  objects left while these cases settled, so their runs start with different '
              f'numbers in play: {uneven}', flush=True)
      rows[label] = report_lib.scored(by_case, time.perf_counter() - start) | {
          'settings': settings[suite, label]}
      report_lib.write_report(report_lib.in_order(report, settings), out)
      print(f'  done in {rows[label]["wall_s"]:.0f} s', flush=True)
    for text in report_lib.suite_tables(suite, report_lib.in_order(report, settings)[suite]):
      print('\n' + text)
  report_lib.write_report(report_lib.in_order(report, settings), out)


if __name__ == '__main__':
  sys.exit(main())
