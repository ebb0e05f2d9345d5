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
import pathlib
import sys

from mvcoba_jax import api, video
from mvcoba_jax import config as config_lib
from mvcoba_jax.cli import fail
from mvcoba_jax.evaluation.sources import BASELINES
from mvcoba_jax.sim.scenarios import FIT_BOUND, MAX_FIT_BOUND
from mvcoba_jax.suites import SUITES


def build_parser() -> argparse.ArgumentParser:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  config_lib.add_arguments(parser)
  parser.add_argument('--checkpoint', '--compare', nargs='+', default=[],
                      help='work directories of mvcoba-train runs, or folders written by '
                           'mvcoba-export (e.g. pretrained/mvcoba)')
  parser.add_argument('--baseline', choices=BASELINES,
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
  parser.add_argument('--fit-overlaps', type=float, nargs='?', const=1000 * FIT_BOUND,
                      metavar='MM',
                      help='make cases whose objects interpenetrate as placed valid first: in '
                           'file order, each object moved by the least distance (up, or sideways '
                           'away from what it touches) that clears the objects before it; every '
                           'move is reported, and a case where one would move more than MM '
                           f'(default {1000 * FIT_BOUND:.0f}) is refused')
  parser.add_argument('--allow-bad-cases', '--allow-overlaps', action='store_true',
                      help='evaluate cases that fail the load check (refused otherwise): objects '
                           'that interpenetrate as placed, leave the workspace as the case '
                           'settles, or move more than 1 cm from where the file puts them on '
                           'the table')
  return parser


def main(argv=None) -> int:
  parser = build_parser()
  args = parser.parse_args(argv)
  if args.tables:
    if args.checkpoint or args.baseline or args.online or args.no_repeat or args.resume:
      parser.error('--tables joins earlier results; give it without --checkpoint, --baseline, '
                   '--online, --no-repeat or --resume')
    try:
      api.join_evaluations(args.tables, args.out, overwrite=args.overwrite)
    except config_lib.Error as e:
      return fail(e)
    out = pathlib.Path(args.out)
    print((out / 'results.md').read_text())
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
  if args.fit_overlaps is not None and not 0 < args.fit_overlaps <= 1000 * MAX_FIT_BOUND:
    parser.error(f'--fit-overlaps {args.fit_overlaps:g}: a bound in mm in (0, '
                 f'{1000 * MAX_FIT_BOUND:.0f}]')
  try:
    api.evaluate(args.checkpoint, args.suite, baseline=args.baseline, runs=args.runs,
                 max_actions=args.max_actions, seed=args.seed, protocol=protocol,
                 config=args.config, overrides=args.overrides, blocks=args.blocks,
                 allow_bad_cases=args.allow_bad_cases,
                 fit_overlaps=None if args.fit_overlaps is None else args.fit_overlaps / 1000,
                 out=args.out, resume=args.resume,
                 overwrite=args.overwrite, save_visuals=args.save_visuals, video=args.video)
  except config_lib.Error as e:
    return fail(e)
  return 0


if __name__ == '__main__':
  sys.exit(main())
