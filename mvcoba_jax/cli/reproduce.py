"""Reproduces the paper's comparison in one command: every method x seeds trained for the paper's
3000 actions, every suite evaluated with its 5 runs per case, the tables with our intervals over
seeds beside the paper's figures.

  mvcoba-reproduce [--methods mvcoba mvcoba_2fcn vpg grasp_only mvp cpg] [--seeds 0 1 2]
                   [--actions 3000] [--runs 5] [--suites random ordered occluded]
                   [--workdir runs/reproduction] [--out docs/results/reproduction]
                   [--protocols frozen online]
                   [--config default] [--set KEY=VALUE ...]

A killed reproduction resumes where it stopped: training from each run's latest checkpoint,
evaluation keeping every (suite, policy) row it finished. Each test protocol (--protocols: frozen
in --out, online in --out/online) gets the evaluation's results.json and results.md and
comparison.md (ours beside the paper's, per suite); --out also gets the sweep's training
curves (mean over seeds with a band, one PNG per metric) to --out, and prints the
expected and the actual time (summed over invocations from the runs' logs).
"""
from __future__ import annotations

import argparse
import json
import pathlib
import shutil
import sys
import time

from mvcoba_jax import config as config_lib
from mvcoba_jax import api, folders, methods, paper
from mvcoba_jax.checkpoint import holds_checkpoint
from mvcoba_jax.cli import eval as eval_cli
from mvcoba_jax.cli import fail
from mvcoba_jax.cli import train as train_cli
from mvcoba_jax.suites import SUITES, suite_files

# Rough speeds on a 2-core CPU, native backend, default preset (docs/results/reproduction.md:
# 54144 actions in 88 min, 1350 case runs in 55 min): what the expected wall time is computed from.
TRAIN_ACTIONS_PER_S = 10.0
ONLINE_COST = 2.3  # online over frozen evaluation time: 1.9-2.7 (benchmarks/online_eval.py)
EVAL_S_PER_CASE_RUN = {'frozen': 2.5, 'online': 2.5 * ONLINE_COST}

PROTOCOLS = {
    'frozen': 'the trained network, frozen, acts greedily in every run',
    'online': 'every run starts from the trained network and takes one SGD step after each of '
              'its actions (VPG\'s and the MV-COBA authors\' test protocol)',
}


def training_seconds(workdirs) -> float:
  """Seconds the training iterations of these runs took, from their metrics.jsonl (a resumed
  run's log holds the time of every invocation)."""
  return sum(json.loads(line)['wall_s'] for w in workdirs
             for line in (w / 'metrics.jsonl').read_text().splitlines() if line)


def evaluation_seconds(report: dict) -> float:
  """Seconds the rows of an evaluation's results.json took (compile included)."""
  return sum(row['wall_s'] or 0.0 for rows in report.values() for row in rows.values())


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  config_lib.add_arguments(parser)
  parser.add_argument('--methods', nargs='+', choices=methods.names(),
                      default=list(paper.PAPER_NAMES))
  parser.add_argument('--seeds', nargs='+', type=int, default=[0, 1, 2])
  parser.add_argument('--actions', type=int, default=3000, help='training actions per run')
  parser.add_argument('--runs', type=int, default=5, help='evaluation runs per case')
  parser.add_argument('--max-actions', type=int, default=60, help='action cap per run')
  parser.add_argument('--suites', nargs='+', default=['random', 'ordered', 'occluded'],
                      choices=SUITES)
  parser.add_argument('--workdir', default='runs/reproduction', help='the training sweep')
  parser.add_argument('--out', default='docs/results/reproduction',
                      help='tables (the online protocol\'s in OUT/online)')
  parser.add_argument('--protocols', nargs='+', choices=PROTOCOLS, default=list(PROTOCOLS),
                      help='frozen: the trained network as it is; online: every run goes on '
                           'learning from its own actions (mvcoba-eval --online), as the paper '
                           'tested')
  args = parser.parse_args(argv)
  if args.actions < 1:
    parser.error('--actions must be at least 1')
  try:  # what the evaluation would refuse, refused before the sweep trains
    api.check_work(args.runs, args.max_actions, suite_files(args.suites))
    for protocol in args.protocols:
      folders.claim(protocol_folder(pathlib.Path(args.out), protocol), keep=True)
    if pathlib.Path(args.workdir).exists() and not pathlib.Path(args.workdir).is_dir():
      raise folders.FolderError(f'--workdir {args.workdir} is a file, not a folder')
  except (folders.FolderError, api.EvaluationError) as e:
    return fail(e)
  trainings = len(args.methods) * len(args.seeds)
  cases = sum(len(files) for files in suite_files(args.suites).values())
  expected = (trainings * args.actions / TRAIN_ACTIONS_PER_S
              + sum(EVAL_S_PER_CASE_RUN[p] for p in args.protocols)
              * trainings * cases * args.runs)
  print(f'{trainings} trainings of {args.actions} actions, then {trainings} policies x {cases} '
        f'cases x {args.runs} runs: expected about {expected / 60:.0f} min on a 2-core CPU',
        flush=True)
  start = time.perf_counter()
  workdir = pathlib.Path(args.workdir)
  sweep = ['--workdir', str(workdir), '--methods', *args.methods,
           '--seeds', *map(str, args.seeds), '--set', f'train.total_actions={args.actions}',
           *(['--config', args.config] if args.config else []),
           *(a for o in args.overrides for a in ('--set', o))]
  resume = workdir.is_dir() and any(holds_checkpoint(p) for p in workdir.iterdir())
  code = train_cli.main(sweep + (['--resume'] if resume else []))
  if code:
    return code
  dirs = [workdir / f'{m}-s{s}' for m in args.methods for s in args.seeds]
  texts, eval_s = {}, 0.0
  for protocol in args.protocols:
    out = protocol_folder(pathlib.Path(args.out), protocol)
    code = eval_cli.main(['--checkpoint', *map(str, dirs), '--suite', *args.suites,
                          '--runs', str(args.runs), '--max-actions', str(args.max_actions),
                          '--out', str(out), '--resume']
                         + (['--online'] if protocol == 'online' else []))
    if code:
      return code
    report = json.loads((out / 'results.json').read_text())
    texts[protocol] = (f'Test protocol: {PROTOCOLS[protocol]}.\n\n'
                       + paper.comparisons(report))
    eval_s += evaluation_seconds(report)
  train_s = training_seconds(dirs)
  wall = time.perf_counter() - start
  timing = (f'Expected wall time {expected / 60:.0f} min; spent {(train_s + eval_s) / 60:.0f} min '
            f'({train_s / 60:.0f} training, {eval_s / 60:.0f} evaluating: the sums of the '
            f'runs\' logged times, over every invocation); this invocation {wall / 60:.0f} min.')
  for protocol, text in texts.items():
    (protocol_folder(pathlib.Path(args.out), protocol) / 'comparison.md').write_text(
        f'{text}\n\n{timing}\n')
  out = pathlib.Path(args.out)
  curves = [shutil.copy(path, out) for path in sorted(workdir.glob('curves-*.png'))]
  print('\n' + '\n\n'.join(texts.values()) + f'\n\n{timing}\nwrote comparison.md of each '
        f'protocol under {out} and the sweep\'s training curves '
        f'({", ".join(pathlib.Path(c).name for c in curves)})')
  return 0


def protocol_folder(out: pathlib.Path, protocol: str) -> pathlib.Path:
  """Where a protocol's tables go: --out itself for the frozen one, --out/online for online."""
  return out if protocol == 'frozen' else out / protocol


if __name__ == '__main__':
  sys.exit(main())
