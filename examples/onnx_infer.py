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

from mvcoba_jax.deploy import DeployError, model_file
from mvcoba_jax.deploy.heightmaps import filled
from mvcoba_jax.sim.contract import pixel_to_world, push_length


def choose(session: ort.InferenceSession, color: np.ndarray, depth: np.ndarray,
           changed: bool) -> dict:
  """The graph's greedy action on one state: its `action` and `value` outputs."""
  action, value = session.run(['action', 'value'], {
      'color': color[None], 'depth': depth[None], 'changed': np.array([changed])})
  primitive, rotation, row, col = (int(i) for i in action[0])
  return {'primitive': primitive, 'rotation': rotation, 'row': row, 'col': col,
          'value': float(value[0])}


def to_world(action: dict, depth: np.ndarray, model: dict) -> dict:
  """Adds angle, the world point (x, y, z) of the action, per model.json 'pixel_to_world', and
  how far a push slides (the length it trained with, cut at the workspace's edge as the simulator
  cuts it: `sim.contract.push_length`; 0 for a grasp)."""
  hm = model['heightmap']
  res, half = hm['resolution_m'], hm['workspace_half_m']
  row, col = action['row'], action['col']
  names = {v: k for k, v in model['primitives'].items()}
  angle = model['rotations']['angles_rad'][action['rotation']]
  x, y = pixel_to_world(row, col, res, half)
  push = action['primitive'] == model['primitives']['push']
  return {'primitive_name': names[action['primitive']], **action, 'angle_rad': angle, 'x': x,
          'y': y, 'z': float(depth[hm['views_used'], row, col].max()),
          'push_length_m': float(push_length((x, y), angle, model['config']['env'][
              'push_length'], half)) if push else 0.0}


def load_state(path: pathlib.Path, model: dict, fill_unseen: bool = False
               ) -> tuple[np.ndarray, np.ndarray]:
  """(color, depth) of state.npz, checked against the model's input shapes; for a policy trained
  with `perception.fill_unseen`, each view's unseen cells filled from the others as training
  did, which needs the state's `seen` (V, R, R) booleans."""
  with np.load(path) as data:
    color, depth = (np.asarray(data[k], np.float32) for k in ('color', 'depth'))
    seen = np.asarray(data['seen'], bool) if 'seen' in data else None
  for name, array in (('color', color), ('depth', depth)):
    want = next(i['shape'][1:] for i in model['onnx']['inputs'] if i['name'] == name)
    if list(array.shape) != want:
      raise ValueError(f'{path}: {name} has shape {list(array.shape)}, the model wants {want}')
  if fill_unseen:
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
    model = spec.raw
    color, depth = load_state(args.state, model, spec.fill_unseen)
  except (OSError, KeyError, ValueError, DeployError) as e:
    print(f'error: {e}', file=sys.stderr)
    return 2
  options = ort.SessionOptions()
  options.log_severity_level = 3  # the converter's loose shape annotations only warn
  session = ort.InferenceSession(str(args.model / model['onnx']['file']), options,
                                 providers=['CPUExecutionProvider'])
  action = to_world(choose(session, color, depth, bool(args.changed)), depth, model)
  print(json.dumps(action))
  return 0


if __name__ == '__main__':
  sys.exit(main())
