"""Pictures of what the robot sees: raw camera images and both views' heightmaps, as PNGs.

  python -m mvcoba_jax.viz CASE [--out viz/] [--settle] [--config ...] [--set ...]

CASE is a scenario file (`.scn` or VPG `.txt`). Without --settle the objects are drawn exactly
where the file puts them; with it, after the physics has let them come to rest.
"""
from __future__ import annotations

import argparse
import pathlib
import sys

import cv2
import jax
import numpy as np

from envs import cameras
from envs.scenarios import ScenarioError, case_to_layout, read_case
from envs.tabletop import Tabletop
from mvcoba_jax import config as config_lib
from mvcoba_jax import perception
from mvcoba_jax.runtime import enable_compilation_cache


def _rgb_png(rgb: np.ndarray) -> np.ndarray:
  return (np.clip(rgb, 0, 1) * 255).astype(np.uint8)[..., ::-1]  # OpenCV writes BGR


def _depth_png(depth: np.ndarray, top: float) -> np.ndarray:
  gray = (np.clip(depth / top, 0, 1) * 255).astype(np.uint8)
  return cv2.applyColorMap(gray, cv2.COLORMAP_VIRIDIS)


def write_pictures(env: Tabletop, state, out: pathlib.Path, scale: int = 4) -> list[pathlib.Path]:
  """PNG files of every camera image and heightmap of one environment state."""
  out.mkdir(parents=True, exist_ok=True)
  images = jax.jit(lambda s: cameras.render(env, s))(state)
  obs = jax.jit(lambda s: perception.observe(env, s))(state)
  pictures = {}
  for c, image in enumerate(images):
    far = float(np.asarray(image.depth).max()) or 1.0
    pictures[f'camera{c + 1}_rgb.png'] = _rgb_png(np.asarray(image.rgb))
    pictures[f'camera{c + 1}_depth.png'] = _depth_png(np.asarray(image.depth), far)
    pictures[f'view{c + 1}_color_heightmap.png'] = _rgb_png(np.asarray(obs.color[c]))
    pictures[f'view{c + 1}_depth_heightmap.png'] = _depth_png(np.asarray(obs.depth[c]), 0.15)
  paths = []
  for name, picture in pictures.items():
    big = cv2.resize(picture, None, fx=scale, fy=scale, interpolation=cv2.INTER_NEAREST)
    cv2.imwrite(str(out / name), big)
    paths.append(out / name)
  return paths


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('case', help='scenario file (.scn or VPG .txt)')
  parser.add_argument('--out', default='viz', help='output folder')
  parser.add_argument('--settle', action='store_true', help='let the physics settle the case first')
  config_lib.add_arguments(parser)
  args = parser.parse_args(argv)
  try:
    env = Tabletop(config_lib.from_arguments(args))
    layout = case_to_layout(read_case(args.case), env)
  except (config_lib.ConfigError, ScenarioError) as e:
    parser.error(str(e))
  enable_compilation_cache()
  state = (jax.jit(env.reset_from_case) if args.settle else jax.jit(env.place))(layout)
  for path in write_pictures(env, state, pathlib.Path(args.out)):
    print(path)
  return 0


if __name__ == '__main__':
  sys.exit(main())
