"""How long the deploy path takes from two depth images to an action, on this CPU.

Exports the shipped MV-COBA policy with its ONNX graph, then times, over `--repeats` rounds:
two `--width` x `--height` depth images (a table 0.6 m below each camera, with a few boxes on
it, 16-bit millimetres read from PNG files) to heightmaps, and the ONNX forward with the action
rule. Prints one JSON object with the median of each part and of the whole.

  python benchmarks/deploy.py [--width 640] [--height 480] [--repeats 10]
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import platform
import statistics
import tempfile
import time

import cv2
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--width', type=int, default=640)
  parser.add_argument('--height', type=int, default=480)
  parser.add_argument('--repeats', type=int, default=10)
  args = parser.parse_args()
  from mvcoba_jax import export  # noqa: PLC0415 (JAX only to make the export)
  from mvcoba_jax.deploy import OnnxPolicy, calibration_from_dict, heightmaps, read_depth
  folder = pathlib.Path(tempfile.mkdtemp())
  policy = OnnxPolicy(export.export(ROOT / 'pretrained' / 'mvcoba', folder / 'e')['onnx'].parent)
  w, h, f = args.width, args.height, 0.5 * args.width / np.tan(np.radians(30))
  cameras = []
  for side in (1.0, -1.0):  # looking straight down from 0.6 m, either side of the centre
    pose = [[side, 0, 0, 0.05 * side], [0, -side, 0, 0], [0, 0, -1, 0.6], [0, 0, 0, 1]]
    cameras.append({'width': w, 'height': h, 'fx': f, 'fy': f, 'cx': w / 2 - 0.5,
                    'cy': h / 2 - 0.5, 'camera_to_base': pose, 'depth_scale': 0.001})
  cal = calibration_from_dict({'workspace': {'center': [0.0, 0.0, 0.0]}, 'cameras': cameras})
  rng = np.random.default_rng(0)
  paths = []
  for i in range(2):
    depth = np.full((h, w), 600, np.uint16)
    for _ in range(8):  # boxes 5 cm tall
      r, c = rng.integers(0, h - 40), rng.integers(0, w - 40)
      depth[r:r + 40, c:c + 40] = 550
    paths.append(folder / f'd{i}.png')
    cv2.imwrite(str(paths[-1]), depth)
  parts = {'read_and_heightmaps_s': [], 'act_s': [], 'total_s': []}
  for _ in range(args.repeats + 1):
    start = time.perf_counter()
    color, depth, seen = heightmaps([read_depth(p, c) for p, c in zip(paths, cal.cameras)], cal)
    middle = time.perf_counter()
    policy.act(color, depth, seen, True, cal)
    end = time.perf_counter()
    for key, value in zip(parts, (middle - start, end - middle, end - start)):
      parts[key].append(value)
  print(json.dumps({'benchmark': 'deploy',
                    'settings': {'width': w, 'height': h, 'cameras': 2, 'repeats': args.repeats,
                                 'policy': 'pretrained/mvcoba exported to ONNX',
                                 'cpu_count': os.cpu_count(), 'machine': platform.machine()},
                    'results': {k: statistics.median(v[1:]) for k, v in parts.items()}},
                   indent=1))


if __name__ == '__main__':
  main()
