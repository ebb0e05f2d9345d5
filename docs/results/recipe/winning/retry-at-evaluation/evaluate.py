"""Record script (winning-policy.md, "The retry rule on trained networks"): trained policies
evaluated frozen with `perception.failed_grasp_retries` set at evaluation, which
`config.evaluated` refuses for every `perception.` field (what a network was trained with).
This field changes only which primitive the rule picks after a failed grasp, not what the
network reads, so here the refusal is lifted for it alone.

  python docs/results/recipe/winning/retry-at-evaluation/evaluate.py RETRIES OUT WORKDIR... \
      --suite SUITE_FOLDER...
"""
import argparse
import dataclasses

from mvcoba_jax import api
from mvcoba_jax.config import PerceptionConfig, overrides

FIELD = 'perception.failed_grasp_retries'


def main() -> None:
  parser = argparse.ArgumentParser()
  parser.add_argument('retries', type=int)
  parser.add_argument('out')
  parser.add_argument('workdirs', nargs='+')
  parser.add_argument('--suite', nargs='+', required=True)
  parser.add_argument('--runs', type=int, default=3)
  args = parser.parse_args()
  overrides.FIXED_BY_TRAINING = tuple(
      p for p in overrides.FIXED_BY_TRAINING if p != 'perception.') + tuple(
          f'perception.{f.name}' for f in dataclasses.fields(PerceptionConfig)
          if f'perception.{f.name}' != FIELD)
  api.evaluate(args.workdirs, args.suite, runs=args.runs, out=args.out, resume=True,
               overrides=[f'{FIELD}={args.retries}'], progress=False)


if __name__ == '__main__':
  main()
