"""The paper's comparison as one call (`mvcoba-reproduce`): every method x seed trained for the
paper's 3000 actions, every suite evaluated with 5 runs per case under each test protocol, our
intervals over seeds beside the paper's figures.

    from mvcoba_jax.config import resolve
    from mvcoba_jax.reproduction import reproduce
    reports = reproduce(resolve('tiny'), methods=['mvcoba', 'vpg'], seeds=[0, 1], actions=200,
                        runs=2, suites=['occluded'], workdir='runs/rep', out='runs/rep-tables')
"""
from __future__ import annotations

import dataclasses
import json
import pathlib
import shutil
import time

from mvcoba_jax import api, arguments, folders
from mvcoba_jax import methods as methods_lib
from mvcoba_jax.config import Config, ConfigError, validate
from mvcoba_jax.evaluation import paper
from mvcoba_jax.evaluation import protocols as protocols_lib
from mvcoba_jax.evaluation.report import write_whole
from mvcoba_jax.learner.run_log import plot_sweep
from mvcoba_jax.learner.train import started, sweep_runs
from mvcoba_jax.sim.scenarios import ScenarioError
from mvcoba_jax.suites import CLAIM, suite_files

# Rough speeds on a 2-core CPU, native backend, default preset (docs/results/reproduction.md:
# 54144 actions in 88 min, 1350 case runs in 55 min): what the expected wall time is computed from.
TRAIN_ACTIONS_PER_S = 10.0
FROZEN_S_PER_CASE_RUN = 2.5  # each protocol's `cost` times this
PROTOCOLS = tuple(p.name for p in protocols_lib.PAPER)  # names: the command line's choices


# method -> the preset it trains with in the reproduction: the one it validated best with in the
# per-method screen (docs/results/recipe/baselines/choice.md, by the rule in
# experiments/recipe_table.py; tests/unit/test_recipe_table.py holds the two together).
RECIPES = {'mvcoba': 'reproduction', 'mvcoba_2fcn': 'authors', 'vpg': 'authors',
           'grasp_only': 'reproduction', 'mvp': 'reproduction', 'cpg': 'reproduction'}


def reproduce(config: Config, *, recipes=None, methods=tuple(paper.PAPER_NAMES),
              seeds=(0, 1, 2, 3, 4),
              actions: int = 3000, runs: int = 5, max_actions: int = 60,
              suites=CLAIM,
              workdir='runs/reproduction', out='docs/results/reproduction',
              protocols=tuple(PROTOCOLS), progress: bool = True) -> dict[str, dict]:
  """Trains `methods` x `seeds` for `actions` actions each into WORKDIR/METHOD-sSEED (`api.sweep`),
  each method with its config in `recipes` (method -> Config or preset name; `RECIPES` is the
  screen's choice) or else `config`, evaluates them on `suites` under each of `protocols`
  (`api.evaluate`; frozen in `out`, online in OUT/online) and writes each protocol's comparison.md (ours beside the
  paper's, with the time spent) and the sweep's curves to `out`. Returns protocol -> report.

  Resumes where a killed call stopped: training from each run's latest checkpoint, evaluation
  keeping every row it finished. Raises api.TrainError or api.EvaluationError before anything
  trains when an input cannot serve (the evaluation's work bounds, the output folders).
  """
  call = 'mvcoba_jax.reproduce'
  config = arguments.config(call, config)
  methods = arguments.names(call, 'methods', methods, methods_lib.names())
  seeds = arguments.counts(call, 'seeds', seeds, 0, 2 ** 31 - 1)
  actions = arguments.count(call, 'actions', actions, 1, 10 ** 9)
  # their ranges: `api.check_work`, with the suites' sizes
  runs, max_actions = (arguments.count(call, n, v, -2 ** 63, 2 ** 63)
                       for n, v in (('runs', runs), ('max_actions', max_actions)))
  suites = arguments.names(call, 'suites', suites)
  protocols = [protocols_lib.PROTOCOLS[p] for p in arguments.names(call, 'protocols', protocols,
                                                                   PROTOCOLS)]
  workdir, out = arguments.path(call, 'workdir', workdir), arguments.path(call, 'out', out)
  say = print if arguments.flag(call, 'progress', progress) else (lambda *a, **k: None)
  if out.resolve() == workdir.resolve() or workdir.resolve() in out.resolve().parents:
    raise api.EvaluationError(f'{call}: out {out} lies in workdir {workdir}: the results go '
                              'apart from the runs (choose another --out)')
  try:  # what the evaluation would refuse, refused before the sweep trains
    files = suite_files(list(suites))
    api.check_work(runs, max_actions, files)
    for folder in [workdir, *(p.folder(out) for p in protocols)]:
      folders.check(folder, keep=True)
  except (folders.FolderError, ScenarioError) as e:
    raise api.EvaluationError(str(e)) from None
  recipes = trained_for(call, config, {} if recipes is None else recipes, methods, actions)
  trainings = len(methods) * len(seeds)
  cases = sum(len(f) for f in files.values())
  expected = (trainings * actions / TRAIN_ACTIONS_PER_S
              + sum(FROZEN_S_PER_CASE_RUN * p.cost for p in protocols) * trainings * cases * runs)
  say(f'{trainings} trainings of {actions} actions, then {trainings} policies x {cases} cases x '
      f'{runs} runs: expected about {expected / 60:.0f} min on a 2-core CPU', flush=True)
  start = time.perf_counter()
  dirs = []
  for method in methods:  # each method its own recipe: a sweep of its seeds, resumed if started
    planned = sweep_runs(recipes[method], workdir, [method], seeds)
    dirs += api.sweep(recipes[method], workdir, methods=[method], seeds=seeds,
                      resume=any(started(r, c) for r, c in planned.items()), progress=progress)
  missing = [str(d / 'metrics.jsonl') for d in dirs if not (d / 'metrics.jsonl').is_file()]
  if missing:  # the comparison's timing reads them: refused before the evaluation, not after
    raise api.TrainError(f'{missing[0]} is missing (a run without its log); train that run '
                         'again with --overwrite')
  plot_sweep(dirs, config.train.curve_window, workdir)
  reports, eval_s = {}, 0.0
  for protocol in protocols:
    reports[protocol.name] = api.evaluate(dirs, suites, runs=runs, max_actions=max_actions,
                                          protocol=protocol, out=protocol.folder(out),
                                          resume=True, progress=progress)
    eval_s += evaluation_seconds(reports[protocol.name])
  write_comparisons(reports, protocols, dirs, workdir, out, expected, eval_s, start, say)
  return reports


def trained_for(call: str, config: Config, recipes: dict, methods, actions: int) -> dict:
  """method -> the config it trains with (its entry of `recipes`, else `config`) at `actions`
  actions; api.TrainError for one that cannot be built."""
  if not isinstance(recipes, dict) or not all(isinstance(m, str) for m in recipes):
    raise arguments.ArgumentError(f'{call}: recipes={str(recipes)[:60]!r}: expected a dict of '
                                  'method -> Config or preset name')
  unknown = sorted(set(recipes) - set(methods_lib.names()))
  if unknown:
    raise arguments.ArgumentError(f'{call}: recipes names {unknown[0]!r}, not a method (known: '
                                  f'{", ".join(methods_lib.names())})')
  chosen = {m: arguments.config(call, recipes.get(m, config)) for m in methods}
  try:
    return {m: validate(dataclasses.replace(c, train=dataclasses.replace(
        c.train, total_actions=actions))) for m, c in chosen.items()}
  except ConfigError as e:
    raise api.TrainError(str(e)) from None


def write_comparisons(reports: dict, protocols, dirs, workdir: pathlib.Path, out: pathlib.Path,
                      expected: float, eval_s: float, start: float, say) -> None:
  """Each protocol's comparison.md (ours beside the paper's, with the wall time expected and
  spent) and the sweep's curves, copied from its work directory, into `out`."""
  train_s = training_seconds(dirs)
  timing = (f'Expected wall time {expected / 60:.0f} min; spent {(train_s + eval_s) / 60:.0f} min '
            f'({train_s / 60:.0f} training, {eval_s / 60:.0f} evaluating: the sums of the '
            f'runs\' logged times, over every invocation); this invocation '
            f'{(time.perf_counter() - start) / 60:.0f} min.')
  texts = {p: f'Test protocol: {p.description}.\n\n{paper.comparisons(reports[p.name])}'
           for p in protocols}
  for protocol, text in texts.items():
    write_whole(protocol.folder(out) / 'comparison.md', f'{text}\n\n{timing}\n')
  curves = [pathlib.Path(shutil.copy(p, out)).name for p in sorted(workdir.glob('curves-*.png'))]
  say('\n' + '\n\n'.join(texts.values()) + f'\n\n{timing}\nwrote comparison.md of each '
      f'protocol under {out} and the sweep\'s training curves ({", ".join(curves)})')


def training_seconds(workdirs) -> float:
  """Seconds the training iterations of these runs took, from their metrics.jsonl (a resumed
  run's log holds the time of every invocation)."""
  return sum(json.loads(line)['wall_s'] for w in workdirs
             for line in (w / 'metrics.jsonl').read_text().splitlines() if line)


def evaluation_seconds(report: dict) -> float:
  """Seconds the rows of an evaluation's results.json took (compile included)."""
  return sum(row['wall_s'] or 0.0 for rows in report.values() for row in rows.values())
