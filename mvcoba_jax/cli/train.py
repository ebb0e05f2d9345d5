"""Trains a push-and-grasp Q-network on B tabletops in lockstep, then runs a short evaluation.

  mvcoba-train [--config default|paper|tiny|FILE]
               [--method mvcoba|mvcoba_2fcn|vpg|grasp_only|mvp|cpg] [--set key=value ...]
               [--seed N] [--workdir runs/NAME] [--resume]
               [--distributed [--coordinator HOST:PORT --num-processes N --process-id I]]
  mvcoba-train --methods mvcoba vpg --seeds 0 1 2 --workdir runs/sweep [--resume]

The work directory gets config.json (the resolved config), actions.jsonl (one line per action),
metrics.jsonl (one line per host iteration), checkpoints/ (Orbax, atomic, resumable) and
curves.png (grasp success and action efficiency over the last 200 attempts). With `--methods`
or `--seeds` it is a sweep folder: every method x seed trains in turn into its own
`METHOD-sSEED/`; `--resume` continues those with a checkpoint and starts the others, and
`mvcoba-eval --checkpoint runs/sweep/*` gives each method's interval over the seeds.
"""
from __future__ import annotations

import argparse
import json
import pathlib
import sys

import jax

from mvcoba_jax import api, methods
from mvcoba_jax import config as config_lib
from mvcoba_jax.checkpoint import holds_checkpoint, latest_step
from mvcoba_jax.cli import fail
from mvcoba_jax.run_log import plot_sweep


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
  args = parser.parse_args(argv)
  cluster = (args.coordinator, args.num_processes, args.process_id)
  if not args.distributed and any(v is not None for v in cluster):
    parser.error('--coordinator, --num-processes and --process-id need --distributed')
  if args.resume and args.overwrite:
    parser.error('--resume continues a run and --overwrite replaces it: give one')
  if args.method and args.methods or args.seed is not None and args.seeds:
    parser.error('give --method/--seed for one run or --methods/--seeds for a sweep, not both')
  sweep = bool(args.methods or args.seeds)
  runs = {}  # work directory -> config
  for method in args.methods or [args.method]:
    for seed in args.seeds or [args.seed]:
      overrides = list(args.overrides)
      if method:
        overrides.append(f'network.method={method}')
      if seed is not None:
        overrides.append(f'seed={seed}')
      try:
        config = config_lib.resolve(args.config, overrides)
      except config_lib.ConfigError as e:
        parser.error(str(e))
      name = f'{config.network.method}-s{config.seed}'
      runs[pathlib.Path(args.workdir) / name if sweep else pathlib.Path(args.workdir)] = config
  return args, runs, sweep


def main(argv=None) -> int:
  args, runs, sweep = parse(argv)
  if args.distributed:
    jax.distributed.initialize(coordinator_address=args.coordinator,
                               num_processes=args.num_processes, process_id=args.process_id)
  if sweep and args.resume and not any(holds_checkpoint(w) for w in runs):
    print(f'error: --resume: no run of the sweep in {args.workdir} holds a checkpoint',
          file=sys.stderr)
    return 2
  for i, (workdir, config) in enumerate(runs.items()):
    if sweep:
      print(f'sweep {i + 1}/{len(runs)}: {workdir}', flush=True)
      if args.resume and finished(workdir, config):
        print('  finished already: its last checkpoint, config and greedy evaluation are there')
        continue
    try:
      api.train(config, workdir, resume=args.resume and (holds_checkpoint(workdir) or not sweep),
                overwrite=args.overwrite, eval_actions=args.eval_actions)
    except api.TrainError as e:
      return fail(e)
  if sweep and jax.process_index() == 0:
    window = next(iter(runs.values())).train.curve_window
    for path in plot_sweep(list(runs), window, pathlib.Path(args.workdir)):
      print(f'sweep curves: {path}')
  return 0


def finished(workdir: pathlib.Path, config) -> bool:
  """Whether a run of a sweep has nothing left to do: trained to the end with this very config
  and evaluated (a resumed sweep passes over it without compiling)."""
  step = latest_step(workdir)
  try:
    saved = json.loads((workdir / 'config.json').read_text())
  except (OSError, json.JSONDecodeError):
    return False
  same = saved == json.loads(json.dumps(config_lib.to_dict(config)))  # tuples as JSON lists
  return (step is not None and step >= config.train.total_actions and same
          and (workdir / 'eval_summary.json').is_file())


if __name__ == '__main__':
  sys.exit(main())
