"""Trains a push-and-grasp Q-network on B tabletops in lockstep, then runs a short evaluation.

  mvcoba-train [--config default|paper|tiny|FILE]
               [--method mvcoba|mvcoba_2fcn|vpg|grasp_only|mvp|cpg] [--set key=value ...]
               [--seed N] [--workdir runs/NAME] [--resume]
               [--distributed [--coordinator HOST:PORT --num-processes N --process-id I]]
  mvcoba-train --methods mvcoba vpg --seeds 0 1 2 --workdir runs/sweep [--resume]

The work directory gets config.json (the resolved config), actions.jsonl (one line per action),
metrics.jsonl (one line per host iteration), checkpoints/ (Orbax, atomic, resumable) and
curves.png (grasp success and successful grasps per action over the last 200 attempts). With
`--methods` or `--seeds` it is a sweep folder: every method x seed trains in turn into its own
`METHOD-sSEED/`; `--resume` continues those with a checkpoint and starts the others, and
`mvcoba-eval --checkpoint runs/sweep/*` gives each method's interval over the seeds.
"""
from __future__ import annotations

import argparse
import sys

import jax

from mvcoba_jax import api, methods
from mvcoba_jax import config as config_lib
from mvcoba_jax.cli import fail


def parse(argv):
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  config_lib.add_arguments(parser)
  parser.add_argument('--method', choices=methods.names(), help='sets network.method')
  parser.add_argument('--seed', type=int, help='sets seed')
  parser.add_argument('--methods', nargs='+', choices=methods.names(),
                      help='a sweep: train each of these methods (with each of --seeds)')
  parser.add_argument('--seeds', nargs='+', type=int,
                      help='a sweep: train with each of these seeds (and each of --methods)')
  parser.add_argument('--workdir', default='runs/train', help='output folder')
  parser.add_argument('--resume', action='store_true', help='continue from the latest checkpoint')
  parser.add_argument('--overwrite', action='store_true',
                      help='delete an earlier run in --workdir and start anew (refused otherwise)')
  parser.add_argument('--distributed', action='store_true',
                      help='join the other processes with jax.distributed.initialize() before '
                           'anything else; cluster settings come from the environment (SLURM, '
                           'Kubernetes, ...) unless given below')
  parser.add_argument('--coordinator', help='with --distributed: HOST:PORT of process 0')
  parser.add_argument('--num-processes', type=int, help='with --distributed: processes in all')
  parser.add_argument('--process-id', type=int, help='with --distributed: this process, 0..N-1')
  parser.add_argument('--eval-actions', type=int, default=40,
                      help='greedy actions (over all environments) in the closing evaluation')
  parser.add_argument('--json', action='store_true',
                      help='end with the training and greedy summaries as JSON lines instead '
                           'of a table and the next commands')
  args = parser.parse_args(argv)
  cluster = (args.coordinator, args.num_processes, args.process_id)
  if not args.distributed and any(v is not None for v in cluster):
    parser.error('--coordinator, --num-processes and --process-id need --distributed')
  if args.resume and args.overwrite:
    parser.error('--resume continues a run and --overwrite replaces it: give one')
  if args.method and args.methods or args.seed is not None and args.seeds:
    parser.error('give --method/--seed for one run or --methods/--seeds for a sweep, not both')
  try:
    config = config_lib.resolve(args.config, [
        *args.overrides, *([f'network.method={args.method}'] if args.method else []),
        *([f'seed={args.seed}'] if args.seed is not None else [])])
    if args.methods or args.seeds:  # a sweep: its runs' configs checked before any trains
      api.sweep_runs(config, args.workdir, args.methods, args.seeds)
  except config_lib.ConfigError as e:
    parser.error(str(e))
  return args, config


def main(argv=None) -> int:
  args, config = parse(argv)
  if args.distributed:
    jax.distributed.initialize(coordinator_address=args.coordinator,
                               num_processes=args.num_processes, process_id=args.process_id)
  try:
    if args.methods or args.seeds:
      api.sweep(config, args.workdir, methods=args.methods, seeds=args.seeds,
                resume=args.resume, overwrite=args.overwrite, eval_actions=args.eval_actions,
                json_report=args.json)
    else:
      api.train(config, args.workdir, resume=args.resume, overwrite=args.overwrite,
                eval_actions=args.eval_actions, json_report=args.json)
  except config_lib.Error as e:
    return fail(e)
  return 0


if __name__ == '__main__':
  sys.exit(main())
