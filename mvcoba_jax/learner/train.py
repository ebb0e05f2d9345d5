"""A training run into its work directory, and a sweep of them: `train` is mvcoba-train's call
(`mvcoba_jax.train`), around `Trainer.compiled` of `training.py`: the folder held,
checkpoints restored and written atomically, one log line per action and per call of K actions,
TensorBoard scalars, the curves and a closing greedy check."""
from __future__ import annotations

import dataclasses
import json
import pathlib
import time
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from tensorboardX import SummaryWriter
from tqdm import tqdm

from mvcoba_jax import arguments, folders, runtime
from mvcoba_jax import config as config_lib
from mvcoba_jax import methods as methods_lib
from mvcoba_jax.config import MAX_ACTIONS_LIMIT, Config, Error
from mvcoba_jax.learner import sharding
from mvcoba_jax.sim import physics
from mvcoba_jax.learner.checkpoint import (CheckpointError, Checkpoints, holds_checkpoint,
                                           latest_step)
from mvcoba_jax.learner.run_log import (action_records, plot_curves, plot_sweep, read_records,
                                        summary, write_records)
from mvcoba_jax.learner.training import Trainer


# What a run leaves in its work directory: refused to a new run without `resume` or `overwrite`.
RUN_FILES = ('config.json', 'actions.jsonl', 'metrics.jsonl', 'checkpoints', 'eval_summary.json',
             'curves.png', 'tensorboard')
# The scalars of metrics.jsonl also written as TensorBoard events (`tensorboard --logdir WORKDIR`).
SCALARS = ('loss', 'epsilon', 'grasp_success', 'actions_per_s', 'episodes', 'updates',
           'skipped_updates', 'health_resets')


class TrainError(Error):
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
          eval_actions: int = 40, progress: bool = True, json_report: bool = False) -> TrainResult:
  """Trains `config` into `workdir` to `config.train.total_actions`, then a short greedy check.

  The work directory gets config.json, actions.jsonl (a line per action), metrics.jsonl (a line
  per call of K actions; its scalars also as TensorBoard events in tensorboard/), atomic
  checkpoints every `train.checkpoint_every` calls and at the end, curves.png and
  eval_summary.json.
  `resume` continues from its latest checkpoint; a directory holding an earlier run is refused
  unless `resume` or `overwrite` (which deletes it first). It ends by printing a short table and
  the commands that evaluate and export the run (`closing_report`), or with `json_report` the two
  summaries as JSON lines (`training: {...}`, `greedy evaluation on random drops: {...}`).
  Raises TrainError before anything compiles when the config, directory or checkpoint cannot
  serve. On several devices the tabletops and replay are sharded (`sharding.py`); process 0
  writes the logs.
  """
  call = 'mvcoba_jax.train'
  config, workdir = arguments.config(call, config), arguments.path(call, 'workdir', workdir)
  resume, overwrite = (arguments.flag(call, n, v) for n, v in (('resume', resume),
                                                                ('overwrite', overwrite)))
  eval_actions = arguments.count(call, 'eval_actions', eval_actions, 0, MAX_ACTIONS_LIMIT)
  progress = arguments.flag(call, 'progress', progress)
  json_report = arguments.flag(call, 'json_report', json_report)
  if resume and overwrite:
    raise TrainError(f'{call}: resume continues the run and overwrite deletes it: give one')
  try:  # before anything is created or compiled: a folder held, a file where a folder goes
    if jax.process_index() == 0:  # the lead process holds the folder (the others write beside)
      folders.check(workdir, RUN_FILES, keep=resume, overwrite=overwrite)
  except folders.FolderError as e:
    raise TrainError(str(e)) from None
  for name in ('checkpoints', 'tensorboard'):
    if (workdir / name).exists() and not (workdir / name).is_dir():
      raise TrainError(f'{workdir / name} is a file, where the run\'s {name} go')
  if resume:
    if not holds_checkpoint(workdir):
      raise TrainError(f'resume: {workdir / "checkpoints"} holds no checkpoint')
    resumable(config, workdir)
  problem = physics.device_problem(config.scene)
  if problem:
    raise TrainError(problem)
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
  try:
    return _train(config, trainer, devices, workdir, resume, eval_actions, progress, lead,
                  json_report)
  finally:
    folders.release(workdir)


# What a resumed training may change of the config it was started with: how long it trains, how
# often it saves and logs, and where it computes. Anything else would make one run of two recipes.
RESUME_MAY_CHANGE = ('train.total_actions', 'train.checkpoint_every', 'train.curve_window',
                     *config_lib.RUNTIME_FIELDS)


def resumable(config: Config, workdir: pathlib.Path) -> None:
  """Raises TrainError when `config` differs from the run's saved config.json in a field outside
  `RESUME_MAY_CHANGE` (naming each), or asks for fewer actions than its checkpoint holds."""
  path = workdir / 'config.json'
  try:
    saved = config_lib.from_dict(json.loads(path.read_text()), where=str(path))
  except (OSError, ValueError, config_lib.ConfigError) as e:
    raise TrainError(f'resume: {path}: cannot read the run\'s config ({str(e)[:200]})') from None
  before, now = (config_lib.flat(config_lib.to_dict(c)) for c in (saved, config))
  changed = [f'{k}={before.get(k)!r} -> {now.get(k)!r}' for k in dict.fromkeys([*before, *now])
             if before.get(k) != now.get(k) and k not in RESUME_MAY_CHANGE]
  if changed:
    raise TrainError(f'resume: the config differs from {path} in {", ".join(changed)}; only '
                     f'{", ".join(RESUME_MAY_CHANGE)} may change on resume (train a new run '
                     'for another recipe)')
  done = latest_step(workdir)
  if config.actions_trained < done:
    raise TrainError(f'resume: train.total_actions={config.train.total_actions} is below the '
                     f'{done} actions its latest checkpoint holds')


def _train(config: Config, trainer: Trainer, devices, workdir: pathlib.Path, resume: bool,
           eval_actions: int, progress: bool, lead: bool, json_report: bool) -> TrainResult:
  """`train` once its work directory is held."""
  runtime.setup()
  checkpoints = Checkpoints(workdir)  # every process takes part in saving its shards
  iterate = trainer.compiled()
  per_iteration = config.actions_per_call
  say = print if progress else (lambda *a, **k: None)
  say(f'{config.network.method}: {config.num_envs} tabletops x '
      f'{config.train.steps_per_iteration} actions per call on the '
      f'{trainer.task.env.backend.name} backend; compiling (cached after the first time)...',
      flush=True)
  state, records = _start(config, trainer, checkpoints, workdir, resume, lead, say)
  events = SummaryWriter(str(workdir / 'tensorboard')) if lead else None
  if devices.devices.size > 1:  # data parallel: environments and replay split over the devices
    state = sharding.place(state, devices)

  total = config.train.total_actions
  start, done_before = time.perf_counter(), int(state.actions)
  iteration = done_before // per_iteration
  with tqdm(total=config.actions_trained, initial=done_before, unit='action', desc='training',
            disable=not (lead and progress)) as bar:
    while int(state.actions) < total:
      t0 = time.perf_counter()
      state, log = iterate(state, jnp.bool_(True), jnp.float32(-1.0))
      new = action_records(log, int(state.actions) - per_iteration, len(trainer.task.views))
      records += new
      iteration += 1
      rate = (int(state.actions) - done_before) / (time.perf_counter() - start)
      line = _metrics(iteration, state, log, time.perf_counter() - t0, rate, summary(records))
      if lead:
        write_records(workdir / 'actions.jsonl', new, 'a')
        write_records(workdir / 'metrics.jsonl', [line], 'a')
        for name in SCALARS:
          events.add_scalar(f'train/{name}', line[name], line['actions'])
      bar.update(per_iteration)
      bar.set_postfix(actions_per_s=f'{rate:.2f}', grasp=f'{line["grasp_success"]:.2f}',
                      eps=f'{line["epsilon"]:.2f}', loss=f'{line["loss"]:.3f}')
      if iteration % config.train.checkpoint_every == 0 or int(state.actions) >= total:
        _save(checkpoints, int(state.actions), state,
              {'config': config_lib.to_dict(config), 'iteration': iteration})
        if lead:
          plot_curves(workdir, records, config)
  curve = plot_curves(workdir, records, config) if lead else None
  train_summary = summary(records)
  seconds = time.perf_counter() - start
  if json_report:
    say(f'training: {json.dumps(train_summary)}; wall {seconds:.0f} s; curves {curve}')
  greedy = _greedy_check(iterate, state, eval_actions, per_iteration, len(trainer.task.views))
  if lead:
    (workdir / 'eval_summary.json').write_text(json.dumps(greedy, indent=1))
    for name in ('grasp_success', 'grasps_per_action'):
      events.add_scalar(f'greedy/{name}', greedy[name], int(state.actions))
    events.close()
  if json_report:
    say(f'greedy evaluation on random drops: {json.dumps(greedy)}')
  else:
    say(closing_report(train_summary, greedy, seconds, workdir, curve))
  return TrainResult(state=state, summary=train_summary, greedy=greedy, workdir=workdir,
                     curves=curve)


def closing_report(trained: dict, greedy: dict, seconds: float, workdir, curve) -> str:
  """What a user reads at the end of a run: its actions and time, grasp success and pushes in
  training and in the greedy check, and the commands that evaluate and export it."""
  def grasps(s: dict) -> str:
    if not s['grasp_attempts']:
      return f'no grasps, {s["pushes"]} pushes'
    return (f'grasp success {100 * s["grasp_success"]:.1f} % ({s["grasp_successes"]} of '
            f'{s["grasp_attempts"]}), {s["pushes"]} pushes')
  rate = trained['actions'] / seconds if seconds > 0 else float('nan')
  lines = [f'trained {trained["actions"]} actions in {seconds:.0f} s ({rate:.1f} actions/s)',
           f'  training  {grasps(trained)}',
           f'  greedy    {grasps(greedy)}, {greedy["actions"]} actions on random drops']
  if curve:
    lines.append(f'  curves    {curve}')
  lines += ['next:', f'  mvcoba-eval --checkpoint {workdir} --suite dev-random dev-ordered '
            'dev-occluded --runs 5', f'  mvcoba-export --checkpoint {workdir} --out '
            f'{pathlib.Path(workdir) / "export"}']
  return '\n'.join(lines)


def _start(config: Config, trainer: Trainer, checkpoints: Checkpoints, workdir: pathlib.Path,
           resume: bool, lead: bool, say) -> tuple[Any, list[dict]]:
  """The state to train from (its latest checkpoint with `resume`, else fresh) and the action
  records up to it; the lead process rewrites the logs to match and writes config.json."""
  state = jax.jit(trainer.init)(jax.random.PRNGKey(config.seed))
  records = []
  if resume:
    try:
      state, _ = checkpoints.restore(state, config)
      records = read_records(workdir / 'actions.jsonl', int(state.actions))
    except (CheckpointError, ValueError) as e:
      raise TrainError(str(e)) from None
    say(f'resumed from {checkpoints.directory} at action {int(state.actions)}')
  if lead:
    write_records(workdir / 'actions.jsonl', records, 'w')
    if not resume:
      (workdir / 'metrics.jsonl').write_text('')
    (workdir / 'config.json').write_text(json.dumps(config_lib.to_dict(config), indent=1))
  return state, records


def _metrics(iteration: int, state, log, wall_s: float, rate: float, so_far: dict) -> dict:
  """metrics.jsonl's line of one compiled call."""
  return {'iteration': iteration, 'actions': int(state.actions), 'wall_s': wall_s,
          'actions_per_s': rate, 'loss': float(np.mean(np.asarray(log.loss))),
          'epsilon': float(np.asarray(log.epsilon)[-1]), 'episodes': int(state.episodes),
          'updates': int(state.updates), 'skipped_updates': int(state.skipped_updates),
          'health_resets': int(state.task.env.health_resets.sum()),
          'grasp_success': so_far['grasp_success']}


def _greedy_check(iterate, state, eval_actions: int, per_iteration: int, views: int) -> dict:
  """A short greedy check from the trained state (no learning, epsilon 0): its summary."""
  records = []
  for _ in range(max(1, -(-eval_actions // per_iteration))):
    first = int(state.actions)
    state, log = iterate(state, jnp.bool_(False), jnp.float32(0.0))
    records += action_records(log, first, views)
  return summary(records)


def sweep_runs(config: Config, workdir, methods=None, seeds=None) -> dict[pathlib.Path, Config]:
  """A sweep's runs: `config` for every method x seed (None: the config's own) as
  WORKDIR/METHOD-sSEED -> its config. A method that names its cameras brings them
  (`config.override`). Raises ConfigError for a method or seed the config cannot take."""
  runs = {}
  for method in methods or [config.network.method]:
    for seed in [config.seed] if seeds is None else seeds:
      run = config_lib.override(config, f'network.method={method}')
      runs[pathlib.Path(workdir) / f'{method}-s{seed}'] = config_lib.validate(
          dataclasses.replace(run, seed=seed))
  return runs


def sweep(config: Config, workdir, *, methods=None, seeds=None, resume: bool = False,
          overwrite: bool = False, eval_actions: int = 40, progress: bool = True,
          json_report: bool = False) -> dict[pathlib.Path, TrainResult | None]:
  """Trains every run of `sweep_runs` in turn (`train`), then writes the sweep's curves to
  `workdir` (curves-METRIC.png: each method's mean over its seeds, with a band).

  `resume` passes over a run trained to the end with this very config (None in the result),
  continues one with a checkpoint and starts the others, again where one of this config was
  stopped before its first checkpoint (its logs replaced: they hold no work to keep); it is
  refused when no run of the sweep was started (`started`: a mistyped folder).
  `mvcoba_jax.evaluate` of the runs' folders then gives each method's interval over the seeds.
  """
  call = 'mvcoba_jax.sweep'
  config, workdir = arguments.config(call, config), arguments.path(call, 'workdir', workdir)
  methods = None if methods is None else arguments.names(call, 'methods', methods,
                                                         methods_lib.names())
  seeds = None if seeds is None else arguments.counts(call, 'seeds', seeds, 0, 2 ** 31 - 1)
  for name, value in (('resume', resume), ('overwrite', overwrite), ('progress', progress),
                      ('json_report', json_report)):
    arguments.flag(call, name, value)
  arguments.count(call, 'eval_actions', eval_actions, 0, MAX_ACTIONS_LIMIT)
  try:
    runs = sweep_runs(config, workdir, methods, seeds)
  except config_lib.ConfigError as e:
    raise TrainError(str(e)) from None
  if resume and not any(started(w, c) for w, c in runs.items()):
    raise TrainError(f'resume: no run of the sweep in {workdir} was started (none holds a '
                     'checkpoint or its config.json)')
  say = print if progress else (lambda *a, **k: None)
  results = {}
  for i, (run, run_config) in enumerate(runs.items()):
    say(f'sweep {i + 1}/{len(runs)}: {run}', flush=True)
    if resume and finished(run, run_config):
      say('  finished already: its last checkpoint, config and greedy evaluation are there')
      results[run] = None
      continue
    again = resume and not holds_checkpoint(run) and same_config(run, run_config)
    if again:
      say('  stopped before its first checkpoint: starting it again')
    results[run] = train(run_config, run, resume=resume and holds_checkpoint(run),
                         overwrite=overwrite or again, eval_actions=eval_actions,
                         progress=progress, json_report=json_report)
  if jax.process_index() == 0:
    for path in plot_sweep(list(runs), config.train.curve_window, pathlib.Path(workdir)):
      say(f'sweep curves: {path}')
  return results


def finished(workdir: pathlib.Path, config: Config) -> bool:
  """Whether a run has nothing left to do: trained to the end with this very config and
  evaluated (a resumed sweep passes over it without compiling)."""
  step = latest_step(workdir)
  return (step is not None and step >= config.train.total_actions and same_config(workdir, config)
          and (workdir / 'eval_summary.json').is_file())


def started(workdir: pathlib.Path, config: Config) -> bool:
  """Whether `resume` has something of this run to take up: a checkpoint, or a start of this
  very config stopped before its first checkpoint."""
  return holds_checkpoint(workdir) or same_config(workdir, config)


def same_config(workdir: pathlib.Path, config: Config) -> bool:
  """Whether a run's config.json is this very config."""
  try:
    saved = json.loads((workdir / 'config.json').read_text())
  except (OSError, json.JSONDecodeError):
    return False
  return saved == json.loads(json.dumps(config_lib.to_dict(config)))  # tuples as JSON lists


def _save(checkpoints: Checkpoints, step: int, state, meta: dict) -> None:
  """`Checkpoints.save`, or TrainError when the disk refuses it (Orbax writes a step into a
  temporary folder and renames it when complete: the checkpoints before it are intact)."""
  try:
    checkpoints.save(step, state, meta)
  except Exception as e:  # noqa: BLE001 (Orbax and tensorstore raise many kinds for a full disk)
    earlier = latest_step(checkpoints.directory.parent)
    kept = (f'checkpoint {earlier} is intact, --resume continues from it' if earlier is not None
            else 'no earlier checkpoint')
    cause = str(e).splitlines()[0][:100] if str(e) else ''
    raise TrainError(f'cannot write checkpoint {step} ({kept}) in {checkpoints.directory}: '
                     f'{type(e).__name__}: {cause}') from None
