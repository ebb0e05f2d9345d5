"""An evaluation as one spec: `EvalSpec` (what mvcoba-eval's arguments or a caller's ask),
checked before anything compiles, then `evaluate` runs every policy's row of every suite in
its output folder and `join_evaluations` joins evaluations run apart."""
from __future__ import annotations

import dataclasses
import json
import pathlib
import time

import jax
from tqdm import tqdm

from mvcoba_jax import arguments, folders, runtime, video, viz
from mvcoba_jax import config as config_lib
from mvcoba_jax.config import MAX_ACTIONS_LIMIT, Error
from mvcoba_jax.evaluation import paper, runner
from mvcoba_jax.evaluation import report as report_lib
from mvcoba_jax.evaluation import sources as sources_lib
from mvcoba_jax.evaluation.protocols import FROZEN, PROTOCOLS, Protocol
from mvcoba_jax.learner.task import Task
from mvcoba_jax.policy import PolicyError
from mvcoba_jax.sim import physics
from mvcoba_jax.sim.scenarios import MAX_FIT_BOUND, ScenarioError, case_to_layout, stack_layouts
from mvcoba_jax.suites import cases as suite_cases
from mvcoba_jax.suites import loading, suite_files

# What an evaluation writes to its output folder: refused to a new one without `resume` or
# `overwrite`.
RESULT_FILES = ('results.json', 'results.md', 'comparison.md', 'visuals', 'videos')
MAX_BATCH_RUNS = 4096  # cases x runs of a suite step in one batch, each a whole tabletop


class EvaluationError(Error):
  """An evaluation that cannot run as asked: its policies, cases, settings or output folder;
  the message names which."""


@dataclasses.dataclass(frozen=True)
class EvalSpec:
  """What to evaluate and how, checked when built (`mvcoba_jax.evaluate` documents each field).
  `protocol` is a name of `protocols.PROTOCOLS` or a Protocol."""
  checkpoints: tuple = ()
  suites: tuple = ('all',)
  baseline: str | None = None
  runs: int = 5
  max_actions: int = 60
  seed: int = 0
  protocol: Protocol | str = FROZEN
  config: str | None = None
  overrides: tuple = ()
  blocks: tuple = ()
  allow_bad_cases: bool = False
  fit_overlaps: float | None = None
  out: pathlib.Path | str = 'eval_out'
  resume: bool = False
  overwrite: bool = False
  save_visuals: bool = False
  video: bool = False
  progress: bool = True

  def __post_init__(self):
    call, put = 'mvcoba_jax.evaluate', lambda k, v: object.__setattr__(self, k, v)
    put('checkpoints', tuple(str(p) for p in arguments.paths(call, 'checkpoints',
                                                             self.checkpoints, at_least=0)))
    put('suites', tuple(arguments.names(call, 'suites', self.suites)))
    if self.baseline is not None:
      arguments.choice(call, 'baseline', self.baseline, sources_lib.BASELINES)
    if not self.checkpoints and self.baseline is None:
      raise EvaluationError(f'{call}: nothing to evaluate: give checkpoints or a baseline')
    for name in ('runs', 'max_actions'):  # their ranges: `check_work`, with the suites' sizes
      arguments.count(call, name, getattr(self, name), -2 ** 63, 2 ** 63)
    arguments.count(call, 'seed', self.seed, 0, 2 ** 31 - 1)
    if not isinstance(self.protocol, Protocol):
      put('protocol', PROTOCOLS[arguments.choice(call, 'protocol', self.protocol,
                                                 tuple(PROTOCOLS))])
    if self.config is not None:
      arguments.path(call, 'config', self.config)
    put('overrides', tuple(arguments.names(call, 'overrides', self.overrides, at_least=0)))
    put('blocks', tuple(arguments.names(call, 'blocks', self.blocks, at_least=0,
                                        distinct=False)))
    if self.fit_overlaps is not None:
      arguments.number(call, 'fit_overlaps', self.fit_overlaps, 1e-9, MAX_FIT_BOUND)
    put('out', arguments.path(call, 'out', self.out))
    for name in ('allow_bad_cases', 'resume', 'overwrite', 'save_visuals', 'video', 'progress'):
      arguments.flag(call, name, getattr(self, name))
    if not self.protocol.greedy and self.baseline:
      raise EvaluationError(f'the {self.protocol.name} protocol changes how a trained network '
                            'acts; a baseline has none')
    if self.resume and self.overwrite:
      raise EvaluationError('resume keeps the rows of the output folder and overwrite replaces '
                            'them: give one')

  def say(self, *args, **kwargs) -> None:
    if self.progress:
      print(*args, **kwargs)


def check_work(runs: int, max_actions: int, suites: dict[str, list]) -> None:
  """Refuses runs per case and action caps whose work no evaluation could finish or hold,
  naming the limit; `suites`: name -> its case files."""
  if not 1 <= max_actions <= MAX_ACTIONS_LIMIT:
    raise EvaluationError(f'--max-actions {max_actions}: allowed range [1, {MAX_ACTIONS_LIMIT}]')
  for name, files in suites.items():
    if runs < 1 or runs * len(files) > MAX_BATCH_RUNS:
      raise EvaluationError(f'--runs {runs} x {len(files)} cases of suite {name}: between 1 '
                            f'and {MAX_BATCH_RUNS} runs of a suite step in one batch')


def evaluate(spec: EvalSpec) -> dict:
  """Runs `spec` (`mvcoba_jax.evaluate`): every input checked before anything compiles, then
  each policy's row of each suite, written to `spec.out` after each row."""
  try:  # everything that can be wrong with the input fails here, before any compile
    folders.check(spec.out, RESULT_FILES, keep=spec.resume, overwrite=spec.overwrite)
    files_of = suite_files(list(spec.suites))
    check_work(spec.runs, spec.max_actions, files_of)  # before the cases are read and settled
    base = config_lib.resolve(spec.config, spec.overrides)
    sources = ([sources_lib.trained(path, spec.overrides) for path in spec.checkpoints]
               + ([sources_lib.baseline(spec.baseline)] if spec.baseline else []))
    problem = next(filter(None, (physics.device_problem(c.scene) for c in
                                 [base, *(s.config for s in sources if s.config)])), None)
    if problem:  # as training refuses it
      raise EvaluationError(problem)
    suites = loading.load(files_of, base, spec.blocks, spec.fit_overlaps, spec.allow_bad_cases)
    names = [s.name for s in sources]
    labels = (report_lib.row_labels(list(spec.checkpoints), names[:len(spec.checkpoints)])
              + names[len(spec.checkpoints):])
    labels = [spec.protocol.label(label) for label in labels]
    settings = {(suite, label): row_settings(spec, source, cases, suites.moves.get(suite))
                for suite, cases in suites.cases.items()
                for label, source in zip(labels, sources)}
    report, others, redone = (report_lib.kept_rows(spec.out, settings) if spec.resume
                              else ({}, [], []))
  except (config_lib.ConfigError, ScenarioError, PolicyError, report_lib.ResultsError,
          folders.FolderError) as e:
    raise EvaluationError(str(e)) from None
  if suites.problems and not spec.allow_bad_cases:
    raise EvaluationError('\n  '.join([*suites.hints, *suites.problems]) + '\n(--fit-overlaps '
                          'moves objects that interpenetrate apart; --allow-bad-cases evaluates '
                          'the cases as they are)')
  announce(suites, spec.say)
  try:
    out = folders.claim(spec.out, RESULT_FILES, keep=spec.resume, overwrite=spec.overwrite)
  except folders.FolderError as e:
    raise EvaluationError(str(e)) from None
  if others:
    spec.say(f'kept {len(others)} rows of {out / "results.json"} that this evaluation does not '
             f'redo: {", ".join(f"{suite}/{label}" for suite, label in others)}')
  for suite, label, fields in redone:
    spec.say(f'replacing {suite}/{label} of {out / "results.json"}: it was evaluated with other '
             f'{", ".join(fields) or "settings"}')
  try:
    return _evaluate(spec, suites.cases, labels, sources, settings, report, base)
  finally:
    folders.release(out)


def row_settings(spec: EvalSpec, source: sources_lib.Source, cases, fitted) -> dict:
  """What a results row records of how it was evaluated: a resumed evaluation keeps a row only
  when all of it is the same."""
  policy = source.settings()
  return {'checkpoint': policy['checkpoint'], 'step': policy['step'], 'params': policy['params'],
          'cases': [c.name for c in cases], 'runs': spec.runs, 'max_actions': spec.max_actions,
          'seed': spec.seed, 'set': list(spec.overrides), 'training': policy['training'],
          'training_seed': policy['training_seed'], 'protocol': spec.protocol.name,
          'listed_objects': {c.name: len(c.objects) for c in cases},
          'fit_overlaps_mm': None if spec.fit_overlaps is None else 1000 * spec.fit_overlaps,
          'fitted_mm': fitted}


def announce(suites: loading.Suites, say) -> None:
  """Says what fitting moved and which lines of VPG's files are out of play."""
  for suite, moves in suites.moves.items():
    moved = {case: m for case, m in moves.items() if m['lines_mm']}
    say(f'{suite}: --fit-overlaps moved objects in {len(moved)} of {len(moves)} cases' + ''.join(
        f'\n  {case}: max {m["max_mm"]:.1f} mm, mean {m["mean_mm"]:.1f} mm over its objects '
        f'(lines {", ".join(f"{line}: {d:.1f}" for line, d in m["lines_mm"].items())} mm)'
        for case, m in moved.items()))
  for suite, cases in suites.cases.items():
    parked = sum(len(c.parked_lines) for c in cases)
    if parked:
      say(f'{suite}: {parked} lines of its VPG files lie outside VPG\'s workspace (objects VPG '
          'parked) and are not in play')


def _evaluate(spec: EvalSpec, cases_of, labels, sources, settings, report, base) -> dict:
  """`evaluate` once its inputs are checked and its output folder is held."""
  out = spec.out
  pictures = [name for name, wanted in (('visuals', spec.save_visuals), ('videos', spec.video))
              if wanted and (out / name).exists() and not (out / name).is_dir()]
  if pictures:
    raise EvaluationError(f'{out}: {", ".join(pictures)} is a file, where the runs\' pictures go')
  runtime.setup()
  try:
    for suite, cases in cases_of.items():
      rows = report.setdefault(suite, {})
      for label, source in zip(labels, sources):
        if label in rows:
          spec.say(f'{suite}: {label}: kept from {out / "results.json"}', flush=True)
          continue
        rows[label] = _row(spec, suite, cases, label, source, base) | {
            'settings': settings[suite, label]}
        # A row's programs hold its policy and tabletop as static arguments, so no other row can
        # reuse them; kept, they add about a thousand memory mappings a row until LLVM cannot
        # map another (a process evaluating 40 to 60 rows crashed so).
        jax.clear_caches()
        report_lib.write_report(report_lib.in_order(report, settings), out)
        spec.say(f'  done in {rows[label]["wall_s"]:.0f} s', flush=True)
      for text in report_lib.suite_tables(suite, report_lib.in_order(report, settings)[suite]):
        spec.say('\n' + text)
    report = report_lib.in_order(report, settings)
    report_lib.write_report(report, out)
  except report_lib.ResultsError as e:
    raise EvaluationError(str(e)) from None
  spec.say(f'\nwrote {out / "results.json"} and {out / "results.md"}')
  return report


def _row(spec: EvalSpec, suite: str, cases, label: str, source: sources_lib.Source,
         base) -> dict:
  """One policy's row of one suite: its runs, their pictures when asked, the scored counts."""
  runs, say = spec.runs, spec.say
  config = suite_cases.suite_config(source.config if source.trained else base,
                                    suite_cases.pool_for(cases))
  task = Task.build(config, source.views, frames=video.FRAMES_PER_PRIMITIVE if spec.video else 0)
  actor = source.actor(config, spec.protocol)
  layouts = stack_layouts([case_to_layout(c, task.env) for c in cases for _ in range(runs)])
  keys = jax.random.split(jax.random.PRNGKey(spec.seed), len(cases) * runs)
  say(f'{suite}: {label}, {len(cases)} cases x {runs} runs, up to {spec.max_actions} actions '
      'each; compiling and running...', flush=True)
  start = time.perf_counter()
  with tqdm(total=spec.max_actions, unit='action', desc=f'  {suite}',
            disable=not spec.progress) as bar:
    def progress(done, finished, bar=bar, n=len(layouts.in_play)):
      bar.set_postfix_str(f'{int(finished)}/{n} runs finished', refresh=False)
      bar.update(int(done) - bar.n)
    result = runner.evaluate(task, actor, layouts, keys, spec.max_actions,
                             record=spec.save_visuals or spec.video, progress=progress)
    logs = runner.run_logs(result, task)
  names = [c.name for c in cases]
  run_names = [f'{n}_run{r}' for n in names for r in range(runs)]
  where = pathlib.Path(pathlib.Path(suite).name) / label.replace(':', '_')
  if spec.video:
    paths = video.write_run_videos(jax.device_get(result.trace), run_names,
                                   spec.out / 'videos' / where, task)
    say(f'  {len(paths)} videos in {spec.out / "videos" / where}', flush=True)
  if spec.save_visuals:
    folder = spec.out / 'visuals' / where
    viz.write_run_strips(jax.device_get(result.trace), run_names, folder, task)
    lost = runner.losses(result.trace, run_names, task)
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
