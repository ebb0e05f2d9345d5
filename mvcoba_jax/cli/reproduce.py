"""Reproduces the paper's comparison in one command: every method x seeds trained for the paper's
3000 actions, every suite evaluated with its 5 runs per case, the tables with our intervals over
seeds beside the paper's figures (`mvcoba_jax.reproduction.reproduce`).

  mvcoba-reproduce [--methods mvcoba mvcoba_2fcn vpg grasp_only mvp cpg] [--seeds 0 1 2 3 4]
                   [--actions 3000] [--runs 5] [--suites random ordered occluded vpg]
                   [--workdir runs/reproduction] [--out docs/results/reproduction]
                   [--protocols frozen online]
                   [--config default] [--set KEY=VALUE ...]

Each method trains the preset it validated best with (`reproduction.RECIPES`) unless --config
or --set names one config for all. A killed reproduction resumes where it stopped: training from each run's latest checkpoint,
evaluation keeping every (suite, policy) row it finished. Each test protocol (--protocols: frozen
in --out, online in --out/online) gets the evaluation's results.json and results.md and
comparison.md (ours beside the paper's, per suite); --out also gets the sweep's training
curves (mean over seeds with a band, one PNG per metric), and the command prints the
expected and the actual time (summed over invocations from the runs' logs).
"""
from __future__ import annotations

import argparse
import sys

from mvcoba_jax import methods
from mvcoba_jax import config as config_lib
from mvcoba_jax.cli import fail
from mvcoba_jax.evaluation import paper
from mvcoba_jax.reproduction import PROTOCOLS, RECIPES, reproduce
from mvcoba_jax.suites import CLAIM, SUITES


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  config_lib.add_arguments(parser)
  parser.add_argument('--methods', nargs='+', choices=methods.names(),
                      default=list(paper.PAPER_NAMES))
  parser.add_argument('--seeds', nargs='+', type=int, default=[0, 1, 2, 3, 4],
                      help='training seeds (5: the fewest a claim between methods needs)')
  parser.add_argument('--actions', type=int, default=3000, help='training actions per run')
  parser.add_argument('--runs', type=int, default=5, help='evaluation runs per case')
  parser.add_argument('--max-actions', type=int, default=60, help='action cap per run')
  parser.add_argument('--suites', nargs='+', default=list(CLAIM), choices=SUITES,
                      help='the sealed suites and VPG\'s cases by default; run once per claim')
  parser.add_argument('--workdir', default='runs/reproduction', help='the training sweep')
  parser.add_argument('--out', default='docs/results/reproduction',
                      help='tables (the online protocol\'s in OUT/online)')
  parser.add_argument('--protocols', nargs='+', choices=PROTOCOLS, default=list(PROTOCOLS),
                      help='frozen: the trained network as it is; online: every run goes on '
                           'learning from its own actions (mvcoba-eval --online), as the paper '
                           'tested')
  args = parser.parse_args(argv)
  try:
    config = config_lib.from_arguments(args)
  except config_lib.ConfigError as e:
    parser.error(str(e))
  try:
    # --config or --set: every method trains that config; else each its screened recipe
    recipes = None if args.config or args.overrides else RECIPES
    reproduce(config, recipes=recipes, methods=args.methods, seeds=args.seeds, actions=args.actions,
              runs=args.runs, max_actions=args.max_actions, suites=args.suites,
              workdir=args.workdir, out=args.out, protocols=args.protocols)
  except config_lib.Error as e:
    return fail(e)
  return 0


if __name__ == '__main__':
  sys.exit(main())
