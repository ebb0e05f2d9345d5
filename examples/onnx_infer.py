"""Chooses one push or grasp with an exported MV-COBA Q-network, without JAX.

  python examples/onnx_infer.py --model DIR --state state.npz [--changed 0|1]

DIR is the output of `mvcoba-export`. state.npz holds `color` (V, R, R, 3) RGB in
0..1, `depth` (V, R, R) heights in metres and `seen` (V, R, R) booleans: the heightmaps of every
camera view (`mvcoba-viz --save-state` writes one; `seen` is needed by a policy that fills
unseen cells). `--changed`
says whether the previous action changed the scene (1 before the first action), which the
change-observation rule of MV-COBA needs. Prints the action as one line of JSON.

The ONNX graph decides (network, rotations, the method's action rule and argmax: model.json,
'onnx'); only pixel -> world runs here. For depth images of calibrated cameras, the checks before
a robot acts and an action in its frame, see `mvcoba_jax.deploy` and examples/robot_loop.py.
"""
from __future__ import annotations

import argparse
import json
import pathlib
import sys

import numpy as np
import onnxruntime as ort
from onnxruntime.capi import onnxruntime_pybind11_state as ort_errors

from mvcoba_jax.deploy import DeployError, model_file
from mvcoba_jax.deploy.policy import check_graph
from mvcoba_jax.sim.contract import filled
from mvcoba_jax.sim.contract import pixel_to_world, push_length


def choose(session: ort.InferenceSession, color: np.ndarray, depth: np.ndarray,
           changed: bool) -> dict:
  """The graph's greedy action on one state: its `action` and `value` outputs."""
  action, value = session.run(['action', 'value'], {
      'color': color[None], 'depth': depth[None], 'changed': np.array([changed])})
  primitive, rotation, row, col = (int(i) for i in action[0])
  return {'primitive': primitive, 'rotation': rotation, 'row': row, 'col': col,
          'value': float(value[0])}


def to_world(action: dict, depth: np.ndarray, spec: model_file.ModelFile) -> dict:
  """Adds angle, the world point (x, y, z) of the action (`sim.contract.pixel_to_world`), and how
  far a push slides (the length it trained with, cut at the workspace's edge as the simulator
  cuts it: `sim.contract.push_length`; 0 for a grasp)."""
  half, row, col = spec.workspace_half_m, action['row'], action['col']
  angle = spec.angles_rad[action['rotation']]
  x, y = pixel_to_world(row, col, spec.resolution_m, half)
  push = action['primitive'] == spec.push
  return {'primitive_name': 'push' if push else 'grasp', **action, 'angle_rad': angle, 'x': x,
          'y': y, 'z': float(depth[list(spec.views_used), row, col].max()),
          'push_length_m': float(push_length((x, y), angle, spec.push_length_m, half)) if push
          else 0.0}


def load_state(path: pathlib.Path, spec: model_file.ModelFile) -> tuple[np.ndarray, np.ndarray]:
  """(color, depth) of state.npz, checked against the policy's views and grid; for a policy
  trained with `perception.fill_unseen`, each view's unseen cells filled from the others as
  training did, which needs the state's `seen` (V, R, R) booleans."""
  with np.load(path) as data:
    color, depth = (np.asarray(data[k], np.float32) for k in ('color', 'depth'))
    seen = np.asarray(data['seen'], bool) if 'seen' in data else None
  grid = [spec.num_views, spec.grid_size, spec.grid_size]
  for name, array, want in (('color', color, [*grid, 3]), ('depth', depth, grid)):
    if list(array.shape) != want:
      raise ValueError(f'{path}: {name} has shape {list(array.shape)}, the model wants {want}')
  if spec.fill_unseen:
    if seen is None or seen.shape != depth.shape:
      raise ValueError(f'{path}: this policy fills unseen cells and needs seen, booleans of the '
                       f'depth\'s shape {list(depth.shape)}')
    color, depth = filled(color, depth, seen)
  return color, depth


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--model', required=True, type=pathlib.Path, help='export folder')
  parser.add_argument('--state', required=True, type=pathlib.Path, help='npz: color, depth')
  parser.add_argument('--changed', type=int, choices=(0, 1), default=1,
                      help='whether the previous action changed the scene (default 1)')
  args = parser.parse_args(argv)
  try:
    spec = model_file.read(args.model)  # checked: format, grid, views, rotations
    if not spec.graph_decides:
      raise DeployError(f'{args.model}: an export whose graph leaves the rule out; export again')
    color, depth = load_state(args.state, spec)
    options = ort.SessionOptions()
    options.log_severity_level = 3  # the converter's loose shape annotations only warn
    onnx_file = args.model / spec.onnx_file
    session = ort.InferenceSession(str(onnx_file), options, providers=['CPUExecutionProvider'])
    check_graph(session, spec, onnx_file)  # names, types and shapes as model.json says
  except (OSError, KeyError, ValueError, DeployError, ort_errors.Fail,
          ort_errors.InvalidGraph, ort_errors.InvalidProtobuf, ort_errors.NoSuchFile) as e:
    print(f'error: {str(e)[:300]}', file=sys.stderr)
    return 2
  action = to_world(choose(session, color, depth, bool(args.changed)), depth, spec)
  print(json.dumps(action))
  return 0


if __name__ == '__main__':
  sys.exit(main())
