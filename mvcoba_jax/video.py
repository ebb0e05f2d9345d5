"""Run videos: the scene from a camera that sees the gripper, a few frames per primitive, the
chosen action and its outcome written on them; one MP4 per evaluation run (OpenCV's writer).

The frames are the qpos snapshots an evaluation records with `Task.build(config, views, frames=F)`
(`evaluation.Trace.frames`). They are drawn here, on the host, by casting one ray per pixel with
MuJoCo (`mujoco.batch`), every geom group included, and shading each hit by the surface's normal:
no OpenGL, so it works on any CPU.
"""
from __future__ import annotations

import pathlib

import cv2
import mujoco
import numpy as np
from mujoco import batch as mjbatch

from mvcoba_jax.learner.task import Task
from mvcoba_jax.sim import cameras
from mvcoba_jax.sim.config import CameraConfig
from mvcoba_jax.sim.contract import pixel_to_world
from mvcoba_jax.sim.primitives import GRASP
from mvcoba_jax.sim.scene import camera_xyaxes

CAMERA = CameraConfig(pos=(0.3, -0.36, 0.4), target=(0.0, 0.0, 0.03), width=320, height=240,
                      fovy_deg=50.0)
FRAMES_PER_PRIMITIVE = 6
FPS = 6  # one primitive a second
LIGHT = np.array([0.3, -0.4, 1.0]) / np.linalg.norm([0.3, -0.4, 1.0])
BACKGROUND = (40, 40, 40)
ALL_GROUPS = (1,) * mujoco.mjNGROUP


def camera_frame(cam: CameraConfig) -> np.ndarray:
  """(3, 3) world axes of the camera as columns: right, up, back (it looks along -back)."""
  right, up = camera_xyaxes(cam).reshape(2, 3)
  return np.stack([right, up, np.cross(right, up)], axis=1)


def world_rays(cam: CameraConfig) -> np.ndarray:
  """(H * W, 3) world directions of the camera's pixels, row-major from the top-left."""
  return cameras.pixel_rays(cam).reshape(-1, 3).astype(np.float64) @ camera_frame(cam).T


def project(cam: CameraConfig, point) -> tuple[int, int]:
  """(column, row) of the pixel that shows world `point`."""
  local = camera_frame(cam).T @ (np.asarray(point, float) - cam.pos)
  focal = cameras.focal_length(cam)
  return (int(round(cam.width / 2 + focal * local[0] / -local[2])),
          int(round(cam.height / 2 - focal * local[1] / -local[2])))


def render(env, qpos, mocap_pos, mocap_quat, slot_color, cam: CameraConfig = CAMERA):
  """(F, H, W, 3) uint8 BGR pictures of the states qpos (F, nq) of one tabletop."""
  m, index = env.scene.mj_model, env.scene.index
  f = qpos.shape[0]
  b = mjbatch.Batch(m, f)
  b.qpos[:] = qpos
  b.mocap_pos[:] = np.broadcast_to(mocap_pos, b.mocap_pos.shape)
  b.mocap_quat[:] = np.broadcast_to(mocap_quat, b.mocap_quat.shape)
  directions = world_rays(cam)
  origins = np.broadcast_to(np.asarray(cam.pos, float), directions.shape)
  dist, geom = b.ray(origins, directions, geomgroup=ALL_GROUPS)
  colors = m.geom_rgba[:, :3].copy()
  slots = index.geom_slot >= 0
  colors[slots] = slot_color[index.geom_slot[slots]] / 255.0
  hit = dist >= 0
  points = (origins + np.maximum(dist, 0)[..., None] * directions).reshape(
      f, cam.height, cam.width, 3)
  normal = np.cross(np.gradient(points, axis=2), np.gradient(points, axis=1))
  normal /= np.maximum(np.linalg.norm(normal, axis=-1, keepdims=True), 1e-12)
  shade = 0.35 + 0.65 * np.abs(normal @ LIGHT)
  rgb = colors[np.maximum(geom, 0)].reshape(f, cam.height, cam.width, 3) * shade[..., None]
  image = np.where(hit.reshape(f, cam.height, cam.width, 1), rgb * 255, BACKGROUND[::-1])
  return np.clip(image, 0, 255).astype(np.uint8)[..., ::-1]


def _caption(image, lines) -> None:
  for i, text in enumerate(lines):
    cv2.putText(image, text, (6, 16 + 16 * i), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255),
                1, cv2.LINE_AA)


def write_run_videos(trace, names: list[str], out: pathlib.Path, task: Task,
                     cam: CameraConfig = CAMERA) -> list[pathlib.Path]:
  """An MP4 per run (`names[i]` names run i's file) of a recorded evaluation's trace (host
  arrays): every action the run took, `Trace.frames` pictures each."""
  out.mkdir(parents=True, exist_ok=True)
  env = task.env
  res, half = task.perception.heightmap_resolution, env.config.scene.workspace_half
  k = env.config.env.num_rotations
  paths = []
  for i, name in enumerate(names):
    paths.append(out / f'{name}.mp4')
    writer = cv2.VideoWriter(str(paths[-1]), cv2.VideoWriter_fourcc(*'mp4v'), FPS,
                             (cam.width, cam.height))
    for t in np.flatnonzero(trace.active[i]):
      frames = render(env, trace.frames[i, t], trace.mocap_pos[i, t], trace.mocap_quat[i, t],
                      trace.slot_color[i, t], cam)
      grasp = trace.primitive[i, t] == GRASP
      x, y = pixel_to_world(trace.row[i, t], trace.col[i, t], res, half)
      what = (f'{t + 1}: {"grasp" if grasp else "push"} at ({x:+.3f}, {y:+.3f}) m, '
              f'{360 * trace.rotation[i, t] / k:.1f} deg')
      lost = int(trace.left_workspace[i, t].sum())
      outcome = ('picked' if trace.grasp_success[i, t] else 'missed') if grasp else 'pushed'
      outcome += f', {lost} left the workspace' if lost else ''
      target = project(cam, (x, y, 0.0))
      for j, frame in enumerate(frames):
        frame = np.ascontiguousarray(frame)
        cv2.drawMarker(frame, target, (0, 255, 255), cv2.MARKER_CROSS, 10, 1)
        _caption(frame, [name, what] + ([outcome] if j == len(frames) - 1 else []))
        writer.write(frame)
    writer.release()
  return paths
