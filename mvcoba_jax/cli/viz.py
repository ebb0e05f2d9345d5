"""Pictures of a case file: each camera's colour and depth image and each view's heightmaps.

  mvcoba-viz CASE [--out viz/] [--settle] [--config ...] [--set ...]

CASE is a scenario file (`.scn` or VPG `.txt`). Without --settle the objects are drawn exactly
where the file puts them; with it, after the physics has let them come to rest.
"""
from __future__ import annotations

import argparse
import pathlib
import sys

import jax

from mvcoba_jax import config as config_lib
from mvcoba_jax import runtime
from mvcoba_jax.sim.scenarios import ScenarioError, case_to_layout, read_case
from mvcoba_jax.sim.tabletop import Tabletop
from mvcoba_jax.viz import write_pictures


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('case', help='scenario file (.scn or VPG .txt)')
  parser.add_argument('--out', default='viz', help='output folder')
  parser.add_argument('--settle', action='store_true', help='let the physics settle the case first')
  parser.add_argument('--blocks', default='vpg',
                      help='block table of a VPG-format case: vpg or mvcoba (the MV-COBA authors\')')
  config_lib.add_arguments(parser)
  args = parser.parse_args(argv)
  try:
    env = Tabletop(config_lib.from_arguments(args))
    scene = env.config.scene
    case = read_case(args.case, scene.workspace_half, scene.workspace_top, args.blocks)
    layout = case_to_layout(case, env)
  except (config_lib.ConfigError, ScenarioError) as e:
    parser.error(str(e))
  runtime.setup()
  state = (jax.jit(env.reset_from_case) if args.settle else jax.jit(env.place))(layout)
  for path in write_pictures(env, state, pathlib.Path(args.out)):
    print(path)
  return 0


if __name__ == '__main__':
  sys.exit(main())
