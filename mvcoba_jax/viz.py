"""Pictures of what the robot sees and does: camera images, heightmaps, and strips of runs."""
from __future__ import annotations

import pathlib

import cv2
import jax
import numpy as np

from mvcoba_jax import perception
from mvcoba_jax.learner.task import Task
from mvcoba_jax.sim import cameras
from mvcoba_jax.sim.contract import pixel_to_world
from mvcoba_jax.sim.geometry import rotation_angle
from mvcoba_jax.sim.primitives import GRASP
from mvcoba_jax.sim.contract import push_length

# Action markers (BGR): a push, a grasp that lifted an object, a grasp that did not.
PUSH_COLOR, GRASP_OK_COLOR, GRASP_FAILED_COLOR = (255, 160, 0), (0, 200, 0), (0, 0, 230)


def _rgb_png(rgb: np.ndarray) -> np.ndarray:
  return (np.clip(rgb, 0, 1) * 255).astype(np.uint8)[..., ::-1]  # OpenCV writes BGR


def _depth_png(depth: np.ndarray, top: float) -> np.ndarray:
  gray = (np.clip(depth / top, 0, 1) * 255).astype(np.uint8)
  return cv2.applyColorMap(gray, cv2.COLORMAP_VIRIDIS)


def write_pictures(task: Task, state, out: pathlib.Path, scale: int = 4) -> list[pathlib.Path]:
  """PNG files of every camera image and heightmap of one environment state."""
  out.mkdir(parents=True, exist_ok=True)
  images = jax.jit(lambda s: cameras.render(task.env, s))(state)
  obs = _observed(task, state)
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


def _observed(task: Task, state) -> perception.Observation:
  """The heightmaps of one environment state, on the host."""
  return jax.device_get(jax.jit(lambda s: perception.observe(task.env, s, task.perception))(state))


def save_state(task: Task, state, path: pathlib.Path) -> pathlib.Path:
  """The heightmaps of every camera view of one environment state as the ONNX example's input
  (`examples/onnx_infer.py --state`): an npz of `color` (V, R, R, 3) RGB in 0..1, `depth`
  (V, R, R) heights in metres, 0 where a view saw nothing (filled from the other views where the
  config fills unseen cells) and `seen` (V, R, R), the cells each view saw."""
  obs = _observed(task, state)
  path.parent.mkdir(parents=True, exist_ok=True)
  np.savez_compressed(path, color=np.asarray(obs.color, np.float32),
                      depth=np.asarray(obs.depth, np.float32), seen=np.asarray(obs.seen, bool))
  return path


def run_strip(trace, run: int, task: Task, scale: int = 3) -> np.ndarray:
  """One run as a left-to-right strip of its steps, each the views' colour heightmaps stacked
  top to bottom with the action drawn on them: a push as an arrow along its direction, a grasp
  as a bar across the fingers' closing line (green if it lifted an object, red if not)."""
  cell, env = task.perception.heightmap_resolution, task.env.config.env
  border = task.env.config.scene.workspace_half
  finger_span = task.env.config.scene.gripper.max_opening / cell * scale
  frames = []
  for t in np.flatnonzero(np.asarray(trace.active[run])):
    views = [cv2.resize(np.ascontiguousarray(v[..., ::-1]), None, fx=scale, fy=scale,
                        interpolation=cv2.INTER_NEAREST) for v in np.asarray(trace.color[run, t])]
    yaw = float(rotation_angle(int(trace.rotation[run, t]), env.num_rotations))
    centre = np.array([trace.col[run, t] + 0.5, trace.row[run, t] + 0.5]) * scale
    is_grasp = int(trace.primitive[run, t]) == GRASP
    if is_grasp:  # the fingers close along (-sin, cos)
      half = finger_span / 2 * np.array([-np.sin(yaw), np.cos(yaw)])
      ends = (centre - half, centre + half)
      color = GRASP_OK_COLOR if bool(trace.grasp_success[run, t]) else GRASP_FAILED_COLOR
    else:  # push: from the pixel along (cos, sin), as far as it went (cut at the border)
      start = pixel_to_world(int(trace.row[run, t]), int(trace.col[run, t]), cell, border)
      length = float(push_length(start, yaw, env.push_length, border)) / cell * scale
      ends = (centre, centre + length * np.array([np.cos(yaw), np.sin(yaw)]))
      color = PUSH_COLOR
    a, b = (tuple(int(round(v)) for v in e) for e in ends)
    for view in views:
      cv2.circle(view, tuple(int(round(v)) for v in centre), scale + 1, color, -1)
      (cv2.line if is_grasp else cv2.arrowedLine)(view, a, b, color, 2)
    frames.append(np.concatenate(views, axis=0))
    frames.append(np.full((frames[-1].shape[0], 4, 3), 255, np.uint8))  # separator
  return np.concatenate(frames[:-1], axis=1) if frames else np.zeros((1, 1, 3), np.uint8)


def write_run_strips(trace, names: list[str], out: pathlib.Path, task: Task) -> list[pathlib.Path]:
  """A PNG strip per run (`names[i]` names run i's file)."""
  out.mkdir(parents=True, exist_ok=True)
  paths = []
  for i, name in enumerate(names):
    paths.append(out / f'{name}.png')
    cv2.imwrite(str(paths[-1]), run_strip(trace, i, task))
  return paths
