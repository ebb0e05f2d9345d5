"""One checked action from a lab's cameras with an exported policy, without JAX.

  python examples/camera_action.py --calibration cal.json --model DIR \
      --depth cam0.png cam1.png [--color cam0-rgb.png cam1-rgb.png] [--changed 0|1]

Needs only `pip install 'mvcoba-jax[deploy]'` (numpy, OpenCV, onnxruntime). DIR is the output of
`mvcoba-export` (model.json and model.onnx); one depth image per camera of the calibration, in
its order (16-bit PNG in the camera's depth scale), and optionally its colour image. `--changed`
says whether the previous action changed the scene (1 before the first action). Prints the action
in the robot's base frame as one line of JSON, or why it was refused (exit 1).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys

from mvcoba_jax.deploy import (DeployError, OnnxPolicy, heightmaps, load_calibration, read_color,
                               read_depth)


def act(calibration, model, depth_files, color_files=None, changed=True):
  """The policy's checked action (`mvcoba_jax.deploy.Action`) on these image files."""
  cal = load_calibration(calibration)
  if len(depth_files) != len(cal.cameras) or (color_files and len(color_files) != len(depth_files)):
    raise DeployError(f'{calibration}: {len(cal.cameras)} cameras, {len(depth_files)} depth and '
                      f'{len(color_files or [])} colour images given')
  depths = [read_depth(path, camera) for path, camera in zip(depth_files, cal.cameras)]
  colors = [read_color(path) for path in color_files] if color_files else None
  return OnnxPolicy(model).act(*heightmaps(depths, cal, colors), changed, cal)


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--calibration', required=True)
  parser.add_argument('--model', required=True, help="mvcoba-export's folder")
  parser.add_argument('--depth', nargs='+', required=True, help='one file per camera')
  parser.add_argument('--color', nargs='+', help='one file per camera')
  parser.add_argument('--changed', type=int, choices=(0, 1), default=1)
  args = parser.parse_args(argv)
  try:
    action = act(args.calibration, args.model, args.depth, args.color, bool(args.changed))
  except DeployError as e:
    print(f'error: {e}', file=sys.stderr)
    return 1
  print(json.dumps(dataclasses.asdict(action)))
  return 0


if __name__ == '__main__':
  sys.exit(main())
