"""Pictures of a case file: each camera's colour and depth image and each view's heightmaps.

  mvcoba-viz CASE [--out viz/] [--settle] [--save-state state.npz] [--config ...] [--set ...]

CASE is a scenario file (`.scn` or VPG `.txt`). Without --settle the objects are drawn exactly
where the file puts them; with it, after the physics has let them come to rest. --save-state
also writes the heightmaps of every view as the input of `examples/onnx_infer.py --state` (the
cameras of the config: `--set network.method=mvp` for MVP's four views).
"""
from __future__ import annotations

import argparse
import pathlib
import sys

import jax

from mvcoba_jax import config as config_lib
from mvcoba_jax import folders, methods, runtime
from mvcoba_jax.learner.task import Task
from mvcoba_jax.sim import physics
from mvcoba_jax.sim.scenarios import ScenarioError, case_to_layout, read_case
from mvcoba_jax.suites.cases import pool_for, suite_config
from mvcoba_jax.viz import save_state, write_pictures


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('case', help='scenario file (.scn or VPG .txt)')
  parser.add_argument('--out', default='viz', help='output folder')
  parser.add_argument('--settle', action='store_true', help='let the physics settle the case first')
  parser.add_argument('--blocks', default='vpg',
                      help='block table of a VPG-format case: vpg or mvcoba (the MV-COBA authors\')')
  parser.add_argument('--save-state', type=pathlib.Path, metavar='FILE',
                      help='also write every view\'s heightmaps as an npz (color, depth): the '
                           'input of examples/onnx_infer.py --state')
  config_lib.add_arguments(parser)
  args = parser.parse_args(argv)
  if args.save_state and args.save_state.exists():
    parser.error(f'--save-state {args.save_state}: exists; remove it or name another file')
  if args.save_state and args.save_state.suffix != '.npz':
    parser.error(f'--save-state {args.save_state}: name an .npz file')
  try:  # where the pictures and the state go, checked before anything renders
    folders.check(args.out)
    if args.save_state:
      folders.check(args.save_state.parent)
  except folders.FolderError as e:
    parser.error(str(e))
  try:
    config = config_lib.from_arguments(args)
    scene = config.scene
    problem = physics.device_problem(scene)
    if problem:  # as training refuses it
      raise config_lib.ConfigError(problem)
    case = read_case(args.case, scene.workspace_half, scene.workspace_top, args.blocks)
    # the slots the case needs
    task = Task.build(suite_config(config, pool_for([case])),
                      methods.get(config.network.method).views)
    layout = case_to_layout(case, task.env)
  except (config_lib.ConfigError, ScenarioError) as e:
    parser.error(str(e))
  runtime.setup()
  env = task.env
  state = (jax.jit(env.reset_from_case) if args.settle else jax.jit(env.place))(layout)
  for path in write_pictures(task, state, pathlib.Path(args.out)):
    print(path)
  if args.save_state:
    print(save_state(task, state, args.save_state))
  return 0


if __name__ == '__main__':
  sys.exit(main())
