"""Exports the latest checkpoint of a training run: params.npz, model.json and model.onnx.

  mvcoba-export --checkpoint WORKDIR --out DIR [--results RESULTS_JSON ...] [--commit SHA]
                [--overwrite]
"""
from __future__ import annotations

import argparse
import sys

from mvcoba_jax.cli import fail
from mvcoba_jax.export import export
from mvcoba_jax.policy import PolicyError


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--checkpoint', required=True, help='work directory of an mvcoba-train run')
  parser.add_argument('--out', required=True, help='output folder')
  parser.add_argument('--results', nargs='+', default=[], metavar='RESULTS_JSON',
                      help='results.json of evaluations of this policy (mvcoba-eval, '
                           'mvcoba-reproduce): their figures for it go into model.json')
  parser.add_argument('--commit', help='the commit of the code that trained it, for model.json')
  parser.add_argument('--overwrite', action='store_true',
                      help='replace an export already in --out')
  args = parser.parse_args(argv)
  try:
    paths = export(args.checkpoint, args.out, args.results, args.commit, args.overwrite)
  except PolicyError as e:
    return fail(e)
  for path in paths.values():
    print(path)
  return 0


if __name__ == '__main__':
  sys.exit(main())
