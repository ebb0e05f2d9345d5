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
import time

import jax
import jax.numpy as jnp
import numpy as np
from tqdm import tqdm

from mvcoba_jax import config as config_lib
from mvcoba_jax import folders, methods, runtime, sharding
from mvcoba_jax.checkpoint import (
  CheckpointError,
  Checkpoints,
  holds_checkpoint,
  latest_step,
)
from mvcoba_jax.cli import fail
from mvcoba_jax.run_log import (
  action_records,
  plot_curves,
  plot_sweep,
  read_records,
  summary,
  write_records,
)
from mvcoba_jax.training import Trainer


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
    code = train(args, config, workdir, args.resume and (holds_checkpoint(workdir) or not sweep))
    if code:
      return code
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


# What a run leaves in its work directory: refused to a new run without --resume or --overwrite.
RUN_FILES = ('config.json', 'actions.jsonl', 'metrics.jsonl', 'checkpoints', 'eval_summary.json',
             'curves.png')


def train(args, config, workdir: pathlib.Path, resume: bool) -> int:
  """One training run into `workdir` (resumed from its latest checkpoint with `resume`)."""
  if resume and not holds_checkpoint(workdir):  # before anything is created or compiled
    print(f'error: --resume: {workdir / "checkpoints"} holds no checkpoint', file=sys.stderr)
    return 2
  devices = sharding.mesh()
  try:  # a config that cannot be built fails here, before the work directory exists
    sharding.check_divisible(config.num_envs, devices)
    trainer = Trainer(config, devices)
  except ValueError as e:
    return fail(e)
  try:  # the lead process holds the folder; the others of a distributed run write beside it
    if jax.process_index() == 0:
      folders.claim(workdir, RUN_FILES, keep=resume, overwrite=args.overwrite)
    else:
      workdir.mkdir(parents=True, exist_ok=True)
  except folders.FolderError as e:
    return fail(e)
  runtime.setup()
  checkpoints = Checkpoints(workdir)  # every process takes part in saving its shards
  lead = jax.process_index() == 0  # the one process that writes logs and curves
  iterate = jax.jit(trainer.iterate)
  per_iteration = config.num_envs * config.train.steps_per_iteration

  print(f'{config.network.method}: {config.num_envs} tabletops x '
        f'{config.train.steps_per_iteration} actions per compiled call on the '
        f'{trainer.env.backend.name} backend; compiling (cached after the first time)...',
        flush=True)
  state = jax.jit(trainer.init)(jax.random.PRNGKey(config.seed))
  actions_path, metrics_path = workdir / 'actions.jsonl', workdir / 'metrics.jsonl'
  if resume:
    try:
      state, meta = checkpoints.restore(state, config)
    except CheckpointError as e:
      return fail(e)
    records = read_records(actions_path, int(state.actions))
    if lead:
      write_records(actions_path, records, 'w')
    print(f'resumed from {checkpoints.directory} at action {int(state.actions)}')
  else:
    records = []
    if lead:
      write_records(actions_path, [], 'w')
      metrics_path.write_text('')
  if lead:
    (workdir / 'config.json').write_text(json.dumps(config_lib.to_dict(config), indent=1))
  if devices.devices.size > 1:  # data parallel: environments and replay split over the devices
    state = sharding.place(state, devices)

  total = config.train.total_actions
  start = time.perf_counter()
  done_before = int(state.actions)
  iteration = done_before // per_iteration
  bar = tqdm(total=total, initial=done_before, unit='action', desc='training', disable=not lead)
  while int(state.actions) < total:
    t0 = time.perf_counter()
    state, log = iterate(state, jnp.bool_(True), jnp.float32(-1.0))
    new = action_records(log, int(state.actions) - per_iteration, len(trainer.views))
    records += new
    iteration += 1
    so_far = summary(records)
    rate = (int(state.actions) - done_before) / (time.perf_counter() - start)
    line = {'iteration': iteration, 'actions': int(state.actions),
            'wall_s': time.perf_counter() - t0, 'actions_per_s': rate, 'loss': float(np.mean(np.asarray(log.loss))),
            'epsilon': float(np.asarray(log.epsilon)[-1]), 'episodes': int(state.episodes),
            'updates': int(state.updates), 'skipped_updates': int(state.skipped_updates),
            'health_resets': int(state.env.health_resets.sum()),
            'grasp_success': so_far['grasp_success']}
    if lead:
      write_records(actions_path, new, 'a')
      write_records(metrics_path, [line], 'a')
    bar.update(per_iteration)
    bar.set_postfix(actions_per_s=f'{rate:.2f}', grasp=f'{so_far["grasp_success"]:.2f}',
                    eps=f'{line["epsilon"]:.2f}', loss=f'{line["loss"]:.3f}')
    if iteration % config.train.checkpoint_every == 0 or int(state.actions) >= total:
      checkpoints.save(int(state.actions), state,
                       {'config': config_lib.to_dict(config), 'iteration': iteration})
      if lead:
        plot_curves(workdir, records, config)
  bar.close()
  curve = plot_curves(workdir, records, config) if lead else None
  train_summary = summary(records)
  print(f'training: {json.dumps(train_summary)}; wall {time.perf_counter() - start:.0f} s; '
        f'curves {curve}')

  # A short greedy evaluation from the trained state: no learning, epsilon 0.
  evaluation, eval_records = state, []
  for _ in range(max(1, -(-args.eval_actions // per_iteration))):
    first = int(evaluation.actions)
    evaluation, log = iterate(evaluation, jnp.bool_(False), jnp.float32(0.0))
    eval_records += action_records(log, first, len(trainer.views))
  result = summary(eval_records)
  if lead:
    (workdir / 'eval_summary.json').write_text(json.dumps(result, indent=1))
  print(f'greedy evaluation on random drops: {json.dumps(result)}')
  return 0


if __name__ == '__main__':
  sys.exit(main())
