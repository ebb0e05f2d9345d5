"""The library calls under the commands: `train` (mvcoba-train's run into a work directory),
`evaluate` and `join_evaluations` (mvcoba-eval), and the policy loader.

    import mvcoba_jax
    from mvcoba_jax.config import resolve
    result = mvcoba_jax.train(resolve('tiny'), 'runs/tiny')
    report = mvcoba_jax.evaluate(['runs/tiny'], ['occluded'], runs=2, out='runs/tiny-eval')
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
from tensorboardX import SummaryWriter
from tqdm import tqdm

from mvcoba_jax import config as config_lib
from mvcoba_jax import arguments, folders, runtime, video, viz
from mvcoba_jax import methods as methods_lib
from mvcoba_jax.config import Config, Error
from mvcoba_jax.evaluation import paper, runner
from mvcoba_jax.evaluation import report as report_lib
from mvcoba_jax.learner import sharding
from mvcoba_jax.learner.checkpoint import (CheckpointError, Checkpoints, holds_checkpoint,
                                           latest_step)
from mvcoba_jax.learner.run_log import (action_records, plot_curves, plot_sweep, read_records,
                                        summary, write_records)
from mvcoba_jax.learner.training import Trainer
from mvcoba_jax.policy import PolicyError, fingerprint
from mvcoba_jax.policy import load as load_policy
from mvcoba_jax.sim.scenarios import (MAX_FIT_BOUND, ScenarioError, case_to_layout, read_case,
                                      stack_layouts)
from mvcoba_jax.sim.shapes import BLOCK_TABLES
from mvcoba_jax.sim.tabletop import Tabletop
from mvcoba_jax.suites import cases as suite_cases
from mvcoba_jax.suites import suite_files


__all__ = ['EvaluationError', 'RESULT_FILES', 'RUN_FILES', 'TrainError', 'TrainResult',
           'evaluate', 'join_evaluations', 'load_policy', 'sweep', 'sweep_runs', 'train']

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
          eval_actions: int = 40, progress: bool = True) -> TrainResult:
  """Trains `config` into `workdir` to `config.train.total_actions`, then a short greedy check.

  The work directory gets config.json, actions.jsonl (a line per action), metrics.jsonl (a line
  per compiled call; its scalars also as TensorBoard events in tensorboard/), atomic checkpoints
  every `train.checkpoint_every` calls and at the end, curves.png and eval_summary.json.
  `resume` continues from its latest checkpoint; a directory holding an earlier run is refused
  unless `resume` or `overwrite` (which deletes it first).
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
    return _train(config, trainer, devices, workdir, resume, eval_actions, progress, lead)
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
  done, per_call = latest_step(workdir), config.num_envs * config.train.steps_per_iteration
  if -(-config.train.total_actions // per_call) * per_call < done:  # whole calls, as trained
    raise TrainError(f'resume: train.total_actions={config.train.total_actions} is below the '
                     f'{done} actions its latest checkpoint holds')


def _train(config: Config, trainer: Trainer, devices, workdir: pathlib.Path, resume: bool,
           eval_actions: int, progress: bool, lead: bool) -> TrainResult:
  """`train` once its work directory is held."""
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
    try:
      records = read_records(actions_path, int(state.actions))
    except ValueError as e:
      raise TrainError(str(e)) from None
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
    events = SummaryWriter(str(workdir / 'tensorboard'))
  if devices.devices.size > 1:  # data parallel: environments and replay split over the devices
    state = sharding.place(state, devices)

  total = config.train.total_actions
  start = time.perf_counter()
  done_before = int(state.actions)
  iteration = done_before // per_iteration
  with tqdm(total=total, initial=done_before, unit='action', desc='training',
            disable=not (lead and progress)) as bar:
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
              'health_resets': int(state.task.env.health_resets.sum()),
              'grasp_success': so_far['grasp_success']}
      if lead:
        write_records(actions_path, new, 'a')
        write_records(metrics_path, [line], 'a')
        for name in SCALARS:
          events.add_scalar(f'train/{name}', line[name], line['actions'])
      bar.update(per_iteration)
      bar.set_postfix(actions_per_s=f'{rate:.2f}', grasp=f'{so_far["grasp_success"]:.2f}',
                      eps=f'{line["epsilon"]:.2f}', loss=f'{line["loss"]:.3f}')
      if iteration % config.train.checkpoint_every == 0 or int(state.actions) >= total:
        _save(checkpoints, int(state.actions), state,
              {'config': config_lib.to_dict(config), 'iteration': iteration})
        if lead:
          plot_curves(workdir, records, config)
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
    for name in ('grasp_success', 'grasps_per_action'):
      events.add_scalar(f'greedy/{name}', greedy[name], int(state.actions))
    events.close()
  say(f'greedy evaluation on random drops: {json.dumps(greedy)}')
  return TrainResult(state=state, summary=train_summary, greedy=greedy, workdir=workdir,
                     curves=curve)


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
          overwrite: bool = False, eval_actions: int = 40,
          progress: bool = True) -> dict[pathlib.Path, TrainResult | None]:
  """Trains every run of `sweep_runs` in turn (`train`), then writes the sweep's curves to
  `workdir` (curves-METRIC.png: each method's mean over its seeds, with a band).

  `resume` passes over a run trained to the end with this very config (None in the result),
  continues one with a checkpoint and starts the others; it is refused when no run holds a
  checkpoint (a mistyped folder). `mvcoba_jax.evaluate` of the runs' folders then gives each
  method's interval over the seeds.
  """
  call = 'mvcoba_jax.sweep'
  config, workdir = arguments.config(call, config), arguments.path(call, 'workdir', workdir)
  methods = None if methods is None else arguments.names(call, 'methods', methods,
                                                         methods_lib.names())
  seeds = None if seeds is None else arguments.counts(call, 'seeds', seeds, 0, 2 ** 31 - 1)
  for name, value in (('resume', resume), ('overwrite', overwrite), ('progress', progress)):
    arguments.flag(call, name, value)
  arguments.count(call, 'eval_actions', eval_actions, 0, MAX_ACTIONS_LIMIT)
  try:
    runs = sweep_runs(config, workdir, methods, seeds)
  except config_lib.ConfigError as e:
    raise TrainError(str(e)) from None
  if resume and not any(holds_checkpoint(w) for w in runs):
    raise TrainError(f'resume: no run of the sweep in {workdir} holds a checkpoint')
  say = print if progress else (lambda *a, **k: None)
  results = {}
  for i, (run, run_config) in enumerate(runs.items()):
    say(f'sweep {i + 1}/{len(runs)}: {run}', flush=True)
    if resume and finished(run, run_config):
      say('  finished already: its last checkpoint, config and greedy evaluation are there')
      results[run] = None
      continue
    results[run] = train(run_config, run, resume=resume and holds_checkpoint(run),
                         overwrite=overwrite, eval_actions=eval_actions, progress=progress)
  if jax.process_index() == 0:
    for path in plot_sweep(list(runs), config.train.curve_window, pathlib.Path(workdir)):
      say(f'sweep curves: {path}')
  return results


def finished(workdir: pathlib.Path, config: Config) -> bool:
  """Whether a run has nothing left to do: trained to the end with this very config and
  evaluated (a resumed sweep passes over it without compiling)."""
  step = latest_step(workdir)
  try:
    saved = json.loads((workdir / 'config.json').read_text())
  except (OSError, json.JSONDecodeError):
    return False
  same = saved == json.loads(json.dumps(config_lib.to_dict(config)))  # tuples as JSON lists
  return (step is not None and step >= config.train.total_actions and same
          and (workdir / 'eval_summary.json').is_file())


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


# What an evaluation writes to its output folder: refused to a new one without `resume` or
# `overwrite`.
RESULT_FILES = ('results.json', 'results.md', 'comparison.md', 'visuals', 'videos')
MAX_ACTIONS_LIMIT = 10_000  # per run: counters and traces grow with it
MAX_BATCH_RUNS = 4096  # cases x runs of a suite step in one batch, each a whole tabletop
PROTOCOLS = ('frozen', 'online', 'no-repeat')
BASELINES = ('heuristic',)  # policies without training (`runner.heuristic_policy`)


class EvaluationError(Error):
  """An evaluation that cannot run as asked: its policies, cases, settings or output folder;
  the message names which."""


def check_work(runs: int, max_actions: int, suites: dict[str, list]) -> None:
  """Refuses runs per case and action caps whose work no evaluation could finish or hold,
  naming the limit."""
  if not 1 <= max_actions <= MAX_ACTIONS_LIMIT:
    raise EvaluationError(f'--max-actions {max_actions}: allowed range [1, {MAX_ACTIONS_LIMIT}]')
  for name, files in suites.items():
    if runs < 1 or runs * len(files) > MAX_BATCH_RUNS:
      raise EvaluationError(f'--runs {runs} x {len(files)} cases of suite {name}: between 1 '
                            f'and {MAX_BATCH_RUNS} runs of a suite step in one batch')


def block_tables(given, suites: list[str]) -> dict[str, str]:
  """`[SUITE=]TABLE` items as suite ('' for every suite) -> block table, each suite named once
  and among the evaluated ones, each table a known one."""
  tables = {}
  for item in given:
    suite, _, table = item.rpartition('=')
    if table not in BLOCK_TABLES or '=' in suite:
      raise EvaluationError(f'--blocks {item[:80]!r}: expected [SUITE=]TABLE with TABLE one of '
                            f'{", ".join(BLOCK_TABLES)}')
    if suite and suite not in suites:
      raise EvaluationError(f'--blocks {item[:80]!r}: {suite[:60]!r} is not an evaluated suite '
                            f'({", ".join(suites)[:120]})')
    if suite in tables:
      raise EvaluationError(f'--blocks names {suite[:60] or "every suite"!r} twice')
    tables[suite] = table
  return tables


def check_blocks(tables: dict[str, str], files_of: dict[str, list]) -> None:
  """Refuses a block table for suites with no VPG-format (.txt) case: it would change nothing."""
  for suite in tables:
    names = [suite] if suite else list(files_of)
    if not any(pathlib.Path(f).suffix == '.txt' for n in names for f in files_of[n]):
      where = f'suite {suite[:60]} has none' if suite else 'no evaluated suite has one'
      raise EvaluationError(f'--blocks {suite + "=" if suite else ""}{tables[suite]}: block '
                            f'tables name the shapes of VPG-format (.txt) cases; {where}')


def evaluate(checkpoints=(), suites=('all',), *, baseline: str | None = None, runs: int = 5,
             max_actions: int = 60, seed: int = 0, protocol: str = 'frozen',
             config: str | None = None, overrides=(), blocks=(), allow_bad_cases: bool = False,
             fit_overlaps: float | None = None, out='eval_out', resume: bool = False,
             overwrite: bool = False,
             save_visuals: bool = False, video: bool = False, progress: bool = True) -> dict:
  """Evaluates trained policies (work directories or exports) and a `baseline` on suites (names
  of `suites.SUITES`, `all`, or paths of case files and folders): every case x `runs` runs of a
  suite in one compiled lockstep loop, each run capped at `max_actions`. `protocol` 'frozen'
  acts greedily with the trained network, 'online' lets every run go on learning from its own
  actions, 'no-repeat' is frozen but never repeats a failed action of its run. `fit_overlaps`
  (a bound in m) moves objects of a case that interpenetrate as the file places them apart
  first (`sim.scenarios.fit_overlaps`), refusing a case where one would move farther.

  Returns the report written to `out` (results.json, results.md, rewritten after each row):
  suite -> row label -> per-case metrics, their means, each run's counts and the settings the
  row was evaluated with. `resume` keeps `out`'s rows of the same settings and evaluates the
  rest; an `out` holding results is refused unless `resume` or `overwrite`. A policy evaluates
  in its own config with `overrides` applied (`config.evaluated`); the baseline in `config`.
  JAX's compiled programs are released after each row (`jax.clear_caches`), the caller's too.
  Raises EvaluationError before anything compiles when an input cannot serve.
  """
  call = 'mvcoba_jax.evaluate'
  checkpoints = arguments.paths(call, 'checkpoints', checkpoints, at_least=0)
  suites = arguments.names(call, 'suites', suites)
  if baseline is not None:
    arguments.choice(call, 'baseline', baseline, BASELINES)
  if not checkpoints and baseline is None:
    raise EvaluationError(f'{call}: nothing to evaluate: give checkpoints or a baseline')
  # their ranges: `check_work`, with the suites' sizes
  runs, max_actions = (arguments.count(call, n, v, -2 ** 63, 2 ** 63)
                       for n, v in (('runs', runs), ('max_actions', max_actions)))
  seed = arguments.count(call, 'seed', seed, 0, 2 ** 31 - 1)
  protocol = arguments.choice(call, 'protocol', protocol, PROTOCOLS)
  if config is not None:
    arguments.path(call, 'config', config)
  overrides = arguments.names(call, 'overrides', overrides, at_least=0)
  blocks = arguments.names(call, 'blocks', blocks, at_least=0, distinct=False)
  if fit_overlaps is not None:
    fit_overlaps = arguments.number(call, 'fit_overlaps', fit_overlaps, 1e-9, MAX_FIT_BOUND)
  out = arguments.path(call, 'out', out)
  for name, value in (('allow_bad_cases', allow_bad_cases), ('resume', resume),
                      ('overwrite', overwrite), ('save_visuals', save_visuals),
                      ('video', video), ('progress', progress)):
    arguments.flag(call, name, value)
  if protocol != 'frozen' and baseline:
    raise EvaluationError(f'the {protocol} protocol changes how a trained network acts; a '
                          'baseline has none')
  if resume and overwrite:
    raise EvaluationError('resume keeps the rows of the output folder and overwrite replaces '
                          'them: give one')
  if fit_overlaps is not None and not 0 < fit_overlaps <= MAX_FIT_BOUND:
    raise EvaluationError(f'fit_overlaps {fit_overlaps!r}: a bound in m in (0, {MAX_FIT_BOUND}]')
  say = print if progress else (lambda *a, **k: None)
  checkpoints = [str(c) for c in checkpoints]
  try:  # everything that can be wrong with the input fails here, before any compile
    folders.check(out, RESULT_FILES, keep=resume, overwrite=overwrite)
    files_of = suite_files(list(suites))
    check_work(runs, max_actions, files_of)
    base = config_lib.resolve(config, overrides)
    bounds = base.scene.workspace_half, base.scene.workspace_top
    tables = block_tables(blocks, list(files_of))
    check_blocks(tables, files_of)
    table_of = {name: tables.get(name, tables.get('', 'vpg')) for name in files_of}
    cases_of = {name: [read_case(f, *bounds, blocks=table_of[name]) for f in files]
                for name, files in files_of.items()}
    moves_of = {}
    if fit_overlaps is not None:
      for name, cases in cases_of.items():
        cases_of[name], moves = suite_cases.fitted(cases, base, fit_overlaps)
        moves_of[name] = {c.name: {'max_mm': round(1000 * max(m), 1),
                                   'mean_mm': round(1000 * sum(m) / len(m), 2),
                                   'lines_mm': {str(o.line): round(1000 * d, 1)
                                                for o, d in zip(c.objects, m) if d}}
                          for c, m in zip(cases, moves)}
    # Fitted objects fall onto what they were lifted from: their neighbours may shift as far.
    settle_move = max(suite_cases.SETTLE_MOVE, fit_overlaps or 0.0)
    bad = [m for cases in cases_of.values()
           for m in suite_cases.case_problems(cases, base, settle_move)]
    hints = [] if not bad or allow_bad_cases else [
        f'{name}: {hint}' for name, files in files_of.items()
        if (hint := suite_cases.other_block_table(files, base, table_of[name]))]
    loaded = [load_policy(path) for path in checkpoints]
    trained = [(config_lib.trained_as(c), c.seed) for c, _, _ in loaded] + [(None, None)]
    sources = [(config_lib.evaluated(c, overrides), model, step) for c, model, step in loaded]
    sources += [baseline] if baseline else []
    names = [runner.source_name(s) for s in sources]
    labels = (report_lib.row_labels(checkpoints, names[:len(checkpoints)])
              + names[len(checkpoints):])
    if protocol != 'frozen':
      labels = [f'{label} [{protocol}]' for label in labels]
    settings = {(suite, label): {
        'checkpoint': path, 'step': None if isinstance(source, str) else source[2],
        'params': None if isinstance(source, str) else fingerprint(source[1]),
        'cases': [c.name for c in cases], 'runs': runs, 'max_actions': max_actions,
        'seed': seed, 'set': list(overrides), 'training': training[0],
        'training_seed': training[1], 'protocol': protocol,
        'listed_objects': {c.name: len(c.objects) for c in cases},
        'fit_overlaps_mm': None if fit_overlaps is None else 1000 * fit_overlaps,
        'fitted_mm': moves_of.get(suite)}
        for suite, cases in cases_of.items()
        for label, source, path, training in zip(labels, sources, checkpoints + [None],
                                                 trained)}
    report, others = report_lib.kept_rows(pathlib.Path(out), settings) if resume else ({}, [])
  except (config_lib.ConfigError, ScenarioError, PolicyError, report_lib.ResultsError,
          folders.FolderError) as e:
    raise EvaluationError(str(e)) from None
  if bad and not allow_bad_cases:
    raise EvaluationError('\n  '.join([*hints, *bad]) + '\n(--fit-overlaps moves objects that '
                          'interpenetrate apart; --allow-bad-cases evaluates the cases as they '
                          'are)')
  for suite, moves in moves_of.items():
    moved = {case: m for case, m in moves.items() if m['lines_mm']}
    say(f'{suite}: --fit-overlaps moved objects in {len(moved)} of {len(moves)} cases' + ''.join(
        f'\n  {case}: max {m["max_mm"]:.1f} mm, mean {m["mean_mm"]:.1f} mm over its objects '
        f'(lines {", ".join(f"{line}: {d:.1f}" for line, d in m["lines_mm"].items())} mm)'
        for case, m in moved.items()))
  for suite, cases in cases_of.items():
    parked = sum(len(c.parked_lines) for c in cases)
    if parked:
      say(f'{suite}: {parked} lines of its VPG files lie outside VPG\'s workspace (objects VPG '
          'parked) and are not in play')
  try:
    out = folders.claim(out, RESULT_FILES, keep=resume, overwrite=overwrite)
  except folders.FolderError as e:
    raise EvaluationError(str(e)) from None
  if others:
    say(f'kept {len(others)} rows of {out / "results.json"} that this evaluation does not '
        f'redo: {", ".join(f"{suite}/{label}" for suite, label in others)}')
  try:
    return _evaluate(cases_of, labels, sources, settings, report, base, protocol, runs,
                     max_actions, seed, out, save_visuals, video, progress)
  finally:
    folders.release(out)


def _evaluate(cases_of, labels, sources, settings, report, base, protocol, runs, max_actions,
              seed, out, save_visuals, video, progress) -> dict:
  """`evaluate` once its inputs are checked and its output folder is held."""
  say = print if progress else (lambda *a, **k: None)
  pictures = [name for name, wanted in (('visuals', save_visuals), ('videos', video))
              if wanted and (out / name).exists() and not (out / name).is_dir()]
  if pictures:
    raise EvaluationError(f'{out}: {", ".join(pictures)} is a file, where the runs\' pictures go')
  runtime.setup()
  try:
    for suite, cases in cases_of.items():
      rows = report.setdefault(suite, {})
      for label, source in zip(labels, sources):
        if label in rows:
          say(f'{suite}: {label}: kept from {out / "results.json"}', flush=True)
          continue
        rows[label] = _row(suite, cases, label, source, base, protocol, runs, max_actions, seed,
                           out, save_visuals, video, progress) | {
                               'settings': settings[suite, label]}
        # A row's programs hold its policy and tabletop as static arguments, so no other row can
        # reuse them; kept, they add about a thousand memory mappings a row until LLVM cannot
        # map another (a process evaluating 40 to 60 rows crashed so).
        jax.clear_caches()
        report_lib.write_report(report_lib.in_order(report, settings), out)
        say(f'  done in {rows[label]["wall_s"]:.0f} s', flush=True)
      for text in report_lib.suite_tables(suite, report_lib.in_order(report, settings)[suite]):
        say('\n' + text)
    report = report_lib.in_order(report, settings)
    report_lib.write_report(report, out)
  except report_lib.ResultsError as e:
    raise EvaluationError(str(e)) from None
  say(f'\nwrote {out / "results.json"} and {out / "results.md"}')
  return report


def _row(suite, cases, label, source, base, protocol, runs, max_actions, seed, out,
         save_visuals, video_too, progress) -> dict:
  """One policy's row of one suite: its runs, their pictures when asked, the scored counts."""
  say = print if progress else (lambda *a, **k: None)
  config = base if isinstance(source, str) else source[0]
  env = Tabletop(suite_cases.suite_config(config, suite_cases.pool_for(cases)),
                 frames=video.FRAMES_PER_PRIMITIVE if video_too else 0)
  policy, views = runner.make_policy(source, env.config, protocol == 'online',
                                         protocol == 'no-repeat')
  layouts = stack_layouts([case_to_layout(c, env) for c in cases for _ in range(runs)])
  keys = jax.random.split(jax.random.PRNGKey(seed), len(cases) * runs)
  say(f'{suite}: {label}, {len(cases)} cases x {runs} runs, up to {max_actions} actions each; '
      'compiling and running...', flush=True)
  start = time.perf_counter()
  with tqdm(total=max_actions, unit='action', desc=f'  {suite}', disable=not progress) as bar:
    def progress(done, finished, bar=bar, n=len(layouts.in_play)):
      bar.set_postfix_str(f'{int(finished)}/{n} runs finished', refresh=False)
      bar.update(int(done) - bar.n)
    result = runner.evaluate(env, policy, views, layouts, keys, max_actions,
                                 record=save_visuals or video_too, progress=progress)
    logs = runner.run_logs(result)
  names = [c.name for c in cases]
  run_names = [f'{n}_run{r}' for n in names for r in range(runs)]
  where = pathlib.Path(pathlib.Path(suite).name) / label.replace(':', '_')
  if video_too:
    paths = video.write_run_videos(jax.device_get(result.trace), run_names,
                                   out / 'videos' / where, env)
    say(f'  {len(paths)} videos in {out / "videos" / where}', flush=True)
  if save_visuals:
    folder = out / 'visuals' / where
    viz.write_run_strips(jax.device_get(result.trace), run_names, folder, env.config)
    lost = runner.losses(result.trace, run_names, env.config)
    (folder / 'losses.json').write_text(json.dumps(lost, indent=1))
    say(f'  visuals in {folder}; {report_lib.loss_summary(lost)}', flush=True)
  by_case = {name: logs[i * runs:(i + 1) * runs] for i, name in enumerate(names)}
  every, short = report_lib.starts(by_case, {c.name: len(c.objects) for c in cases})
  say(f'  objects in play at the start of the runs, of the file\'s: {every}', flush=True)
  if short:
    say(f'  these cases began with fewer objects than their files list (objects left the '
        f'workspace while they settled): {short}', flush=True)
  return report_lib.scored(by_case, time.perf_counter() - start)


def join_evaluations(evaluations, out, *, overwrite: bool = False) -> dict:
  """The results.json of evaluations run apart (their output folders) as one report, scored
  again from their runs, written to `out` with comparison.md (ours beside the paper's); a
  folder given twice, or an `out` holding results without `overwrite`, is refused."""
  call = 'mvcoba_jax.join_evaluations'
  evaluations = arguments.paths(call, 'evaluations', evaluations)
  out = arguments.path(call, 'out', out)
  arguments.flag(call, 'overwrite', overwrite)
  try:
    folders.check(out, RESULT_FILES, overwrite=overwrite)
    report = report_lib.joined_report([str(e) for e in evaluations])
    out = folders.claim(out, RESULT_FILES, overwrite=overwrite)
    try:
      report_lib.write_report(report, out)
      report_lib.write_whole(out / 'comparison.md', paper.comparisons(report) + '\n')
    finally:
      folders.release(out)
  except (report_lib.ResultsError, folders.FolderError) as e:
    raise EvaluationError(str(e)) from None
  return report
