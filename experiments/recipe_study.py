"""The recipe study of MV-COBA (docs/results/recipe.md): each change of the learning recipe alone
from the paper's text, and the authors' whole recipe, trained over seeds and evaluated on the
validation suites (generated apart from the shipped ones), each step resumable; and the chosen
recipe trained longer.

  python experiments/recipe_study.py [--variants NAME ...] [--methods M ...] [--seeds 0 1]
                                     [--runs 3] [--workdir runs/recipe] [--suites DIR ...]
                                     [--landed DIR] [--protocol frozen|online]

Every run trains with `mvcoba-train --method M` into WORKDIR/VARIANT/M-sSEED and is evaluated
with `mvcoba-eval` into WORKDIR/eval/VARIANT-sSEED (MV-COBA) or WORKDIR/eval/VARIANT-M-sSEED; a
run already trained or evaluated is passed over, so the study continues where a killed one
stopped, and with `--landed DIR` (a study's folder under docs/results, as experiments/land.sh
writes it) so does a run whose evaluation landed there from an earlier sitting. `--protocol
online` evaluates with `mvcoba-eval --online` into WORKDIR/eval-online/NAME instead (the paper's
test protocol; the same trained runs). A variant that continues another (`CONTINUES`)
starts from a copy of that variant's finished run of the same seed and resumes it to its own
total. A run of the per-method screen (`preset_*`) whose preset can no longer be chosen for its
method (`recipe_table.ruled_out`, from the evaluations finished here and landed) is passed over.
Then `mvcoba-eval --tables` joins every evaluation into WORKDIR/tables, whose rows group by
training config: one interval per variant over its seeds. Each command, its commit and its wall
time go to WORKDIR/study.jsonl.
"""
from __future__ import annotations

import argparse
import json
import pathlib
import shutil
import subprocess
import sys
import time

import recipe_table
from recipe_variants import CONTINUES, ROOT, VALIDATION, VARIANTS

from mvcoba_jax.learner.checkpoint import holds_checkpoint


def run_name(variant: str, method: str, seed: int) -> str:
  """A run's name: VARIANT-sSEED for MV-COBA (the study's first method), else VARIANT-M-sSEED."""
  return f'{variant}-s{seed}' if method == 'mvcoba' else f'{variant}-{method}-s{seed}'


def commit() -> str:
  head = subprocess.run(['git', 'rev-parse', '--short', 'HEAD'], cwd=ROOT, capture_output=True,
                        text=True).stdout.strip()
  dirty = subprocess.run(['git', 'status', '--porcelain', '--untracked-files=no'], cwd=ROOT,
                         capture_output=True, text=True).stdout.strip()
  return head + ('+changes' if dirty else '')


def run(command: list[str], log: pathlib.Path, what: str) -> bool:
  """Runs a command with its output in `log`'s folder; records it in `log`; True on success."""
  out = log.parent / f'{what}.log'
  start, at = time.time(), commit()
  with open(out, 'w') as f:
    code = subprocess.call(command, stdout=f, stderr=subprocess.STDOUT, cwd=ROOT)
  with open(log, 'a') as f:
    f.write(json.dumps({'what': what, 'command': command, 'commit': at, 'rc': code,
                        'wall_s': round(time.time() - start, 1), 'ended': time.ctime()}) + '\n')
  print(f'{what}: rc {code} in {time.time() - start:.0f} s ({out})', flush=True)
  return code == 0


def cannot_change_choice(variant: str, method: str, *works) -> bool:
  """Whether a run of the per-method screen is futile: its preset is ruled out for the method
  by the evaluations already finished (`recipe_table.ruled_out`)."""
  preset = next((p for p, v in recipe_table.SCREEN.items() if v == variant), None)
  if preset is None:
    return False
  scores = recipe_table.screen_scores(*[w for w in works if w]).get(method, {})
  return preset in recipe_table.ruled_out(scores)


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--variants', nargs='+', default=list(VARIANTS), choices=list(VARIANTS))
  parser.add_argument('--methods', nargs='+', default=['mvcoba'])
  parser.add_argument('--seeds', nargs='+', type=int, default=[0, 1])
  parser.add_argument('--runs', type=int, default=3, help='evaluation runs per case')
  parser.add_argument('--workdir', default='runs/recipe')
  parser.add_argument('--suites', nargs='+', default=[str(VALIDATION / s) for s in
                                                      ('val-random', 'val-ordered',
                                                       'val-occluded', 'val-occluded-high',
                                                       'val-heaps')])
  parser.add_argument('--landed', help='a landed study folder whose evaluations are done')
  parser.add_argument('--protocol', choices=('frozen', 'online'), default='frozen')
  args = parser.parse_args(argv)
  work = (ROOT / args.workdir).resolve()
  work.mkdir(parents=True, exist_ok=True)
  log = work / 'study.jsonl'
  evaluations = []
  landed = pathlib.Path(args.landed).resolve() if args.landed else None
  evals = 'eval' if args.protocol == 'frozen' else f'eval-{args.protocol}'
  online = ['--online'] if args.protocol == 'online' else []
  for seed in args.seeds:  # every variant's first seed before any second
    for variant in args.variants:
      for method in args.methods:
        name = run_name(variant, method, seed)
        if landed and (landed / evals / name / 'done').is_file():
          continue
        if cannot_change_choice(variant, method, work, landed):
          print(f'{name}: passed over: its preset cannot be chosen for {method} whatever it '
                f'scores (recipe_table.ruled_out)', flush=True)
          continue
        train_dir, eval_dir = work / variant / f'{method}-s{seed}', work / evals / name
        if variant in CONTINUES and not train_dir.exists():
          start = work / CONTINUES[variant] / f'{method}-s{seed}'
          if not (start / 'eval_summary.json').is_file():
            print(f'{name}: waits for {start} to finish', flush=True)
            continue
          partial = train_dir.with_name(train_dir.name + '.partial')  # a killed copy is redone
          shutil.rmtree(partial, ignore_errors=True)
          shutil.copytree(start, partial, ignore=shutil.ignore_patterns('eval_summary.json'))
          partial.rename(train_dir)
        if not (train_dir / 'eval_summary.json').is_file():
          if not run(['mvcoba-train', *VARIANTS[variant], '--method', method, '--seed', str(seed),
                      '--workdir', str(train_dir), '--eval-actions', '1']
                     + (['--resume'] if holds_checkpoint(train_dir) else ['--overwrite']),
                     log, f'train-{name}'):
            continue
        if not (eval_dir / 'results.json').is_file() or not (eval_dir / 'done').is_file():
          if not run(['mvcoba-eval', '--checkpoint', str(train_dir), '--suite', *args.suites,
                      '--runs', str(args.runs), '--out', str(eval_dir), '--resume', *online],
                     log, f'{evals}-{name}'):
            continue
          (eval_dir / 'done').touch()
        evaluations.append(str(eval_dir))
  if evaluations:
    tables = work / evals.replace('eval', 'tables')
    run(['mvcoba-eval', '--tables', *evaluations, '--out', str(tables),
         '--overwrite'], log, 'tables')
  return 0


if __name__ == '__main__':
  sys.exit(main())
