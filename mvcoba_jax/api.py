"""The library calls under the commands: what `mvcoba-train` does, as a function of a config
and a work directory, and the policy loader `mvcoba-eval` and `mvcoba-export` use.

    import mvcoba_jax
    from mvcoba_jax.config import resolve
    result = mvcoba_jax.train(resolve('tiny'), 'runs/tiny')
    config, network, step = mvcoba_jax.load_policy('runs/tiny')
"""
from __future__ import annotations

import dataclasses
import json
import pathlib
import time
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from tqdm import tqdm

from mvcoba_jax import config as config_lib
from mvcoba_jax import folders, runtime, sharding
from mvcoba_jax.checkpoint import CheckpointError, Checkpoints, holds_checkpoint
from mvcoba_jax.config import Config
from mvcoba_jax.policy import load as load_policy
from mvcoba_jax.run_log import action_records, plot_curves, read_records, summary, write_records
from mvcoba_jax.training import Trainer

__all__ = ['RUN_FILES', 'TrainError', 'TrainResult', 'load_policy', 'train']

# What a run leaves in its work directory: refused to a new run without `resume` or `overwrite`.
RUN_FILES = ('config.json', 'actions.jsonl', 'metrics.jsonl', 'checkpoints', 'eval_summary.json',
             'curves.png')


class TrainError(ValueError):
  """A run that cannot start or continue: its config, work directory or checkpoint; the message
  names which."""


@dataclasses.dataclass
class TrainResult:
  state: Any  # training.TrainState at the end
  summary: dict  # training's attempts and successes (run_log.summary)
  greedy: dict  # the closing greedy check on random drops (run_log.summary)
  workdir: pathlib.Path
  curves: pathlib.Path | None  # curves.png (None on a process that writes no logs)


def train(config: Config, workdir, *, resume: bool = False, overwrite: bool = False,
          eval_actions: int = 40, progress: bool = True) -> TrainResult:
  """Trains `config` into `workdir` to `config.train.total_actions`, then a short greedy check.

  The work directory gets config.json, actions.jsonl (a line per action), metrics.jsonl (a line
  per compiled call), atomic checkpoints every `train.checkpoint_every` calls and at the end,
  curves.png and eval_summary.json. `resume` continues from its latest checkpoint; a directory
  holding an earlier run is refused unless `resume` or `overwrite` (which deletes it first).
  Raises TrainError before anything compiles when the config, directory or checkpoint cannot
  serve. On several devices the tabletops and replay are sharded (`sharding.py`); process 0
  writes the logs.
  """
  workdir = pathlib.Path(workdir)
  if resume and not holds_checkpoint(workdir):  # before anything is created or compiled
    raise TrainError(f'resume: {workdir / "checkpoints"} holds no checkpoint')
  devices = sharding.mesh()
  try:  # a config that cannot be built fails here, before the work directory exists
    sharding.check_divisible(config.num_envs, devices)
    trainer = Trainer(config, devices)
  except ValueError as e:
    raise TrainError(str(e)) from None
  lead = jax.process_index() == 0  # the one process that writes logs and curves
  try:  # the lead process holds the folder; the others of a distributed run write beside it
    if lead:
      folders.claim(workdir, RUN_FILES, keep=resume, overwrite=overwrite)
    else:
      workdir.mkdir(parents=True, exist_ok=True)
  except folders.FolderError as e:
    raise TrainError(str(e)) from None
  runtime.setup()
  checkpoints = Checkpoints(workdir)  # every process takes part in saving its shards
  iterate = jax.jit(trainer.iterate)
  per_iteration = config.num_envs * config.train.steps_per_iteration
  say = print if progress else (lambda *a, **k: None)

  say(f'{config.network.method}: {config.num_envs} tabletops x '
      f'{config.train.steps_per_iteration} actions per compiled call on the '
      f'{trainer.env.backend.name} backend; compiling (cached after the first time)...',
      flush=True)
  state = jax.jit(trainer.init)(jax.random.PRNGKey(config.seed))
  actions_path, metrics_path = workdir / 'actions.jsonl', workdir / 'metrics.jsonl'
  if resume:
    try:
      state, _ = checkpoints.restore(state, config)
    except CheckpointError as e:
      raise TrainError(str(e)) from None
    records = read_records(actions_path, int(state.actions))
    if lead:
      write_records(actions_path, records, 'w')
    say(f'resumed from {checkpoints.directory} at action {int(state.actions)}')
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
  bar = tqdm(total=total, initial=done_before, unit='action', desc='training',
             disable=not (lead and progress))
  while int(state.actions) < total:
    t0 = time.perf_counter()
    state, log = iterate(state, jnp.bool_(True), jnp.float32(-1.0))
    new = action_records(log, int(state.actions) - per_iteration, len(trainer.views))
    records += new
    iteration += 1
    so_far = summary(records)
    rate = (int(state.actions) - done_before) / (time.perf_counter() - start)
    line = {'iteration': iteration, 'actions': int(state.actions),
            'wall_s': time.perf_counter() - t0, 'actions_per_s': rate,
            'loss': float(np.mean(np.asarray(log.loss))),
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
  say(f'training: {json.dumps(train_summary)}; wall {time.perf_counter() - start:.0f} s; '
      f'curves {curve}')

  # A short greedy check from the trained state: no learning, epsilon 0.
  checked, eval_records = state, []
  for _ in range(max(1, -(-eval_actions // per_iteration))):
    first = int(checked.actions)
    checked, log = iterate(checked, jnp.bool_(False), jnp.float32(0.0))
    eval_records += action_records(log, first, len(trainer.views))
  greedy = summary(eval_records)
  if lead:
    (workdir / 'eval_summary.json').write_text(json.dumps(greedy, indent=1))
  say(f'greedy evaluation on random drops: {json.dumps(greedy)}')
  return TrainResult(state=state, summary=train_summary, greedy=greedy, workdir=workdir,
                     curves=curve)
