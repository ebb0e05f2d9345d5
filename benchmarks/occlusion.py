"""How much of each object every camera sees in a suite's cases, after they settle.

For each case the settled scene is ray-cast from each camera twice, with the case's occluders and
with them parked; an object's visible fraction for a camera is its rays' hits with the occluders
over its hits without them. Prints one JSON object: per case and object (with its case-file line),
the fraction per camera, and the objects that no camera sees well (below `--seen`) or only one
camera does.

  python benchmarks/occlusion.py [--suite occluded] [--seen 0.5]
"""
from __future__ import annotations

import argparse
import json

from mvcoba_jax import runtime
from mvcoba_jax.config import resolve
from mvcoba_jax.sim.scenarios import read_case
from mvcoba_jax.suites import suite_files
from mvcoba_jax.suites.visibility import visibility


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--suite', default='dev-occluded')
  parser.add_argument('--seen', type=float, default=0.5,
                      help='an object counts as seen by a camera above this visible fraction')
  args = parser.parse_args()
  runtime.setup()
  cases = [read_case(f) for f in suite_files([args.suite])[args.suite]]
  print(json.dumps({'benchmark': 'occlusion', 'suite': args.suite, 'seen': args.seen,
                    'cases': visibility(cases, resolve('default'), args.seen)}, indent=1))


if __name__ == '__main__':
  main()
