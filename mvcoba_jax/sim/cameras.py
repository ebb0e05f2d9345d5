"""Two (or more) pinhole RGB-D cameras rendered by ray casting, inside jit.

The physics backend casts the rays (`mj_ray` on CPU threads, or `mjx.ray` traced into the
program); the gripper's geom group is left out so it never hides the scene. The cameras are fixed
in the world, so every ray's origin and direction is computed once. Colour comes from the hit
geom: an object's colour lives in the environment state, so one compiled model serves any
colouring.
"""
from __future__ import annotations

import jax.numpy as jnp
import mujoco
import numpy as np
from flax import struct

from mvcoba_jax.sim.config import CameraConfig


@struct.dataclass
class CameraImage:
  """One camera's picture; pixels with no hit have hit False, geom -1 and depth 0."""
  depth: jnp.ndarray  # (H, W) distance along the optical axis (m)
  rgb: jnp.ndarray  # (H, W, 3) colour 0..1
  geom: jnp.ndarray  # (H, W) int32 id of the hit geom
  points: jnp.ndarray  # (H, W, 3) world coordinates of the hit
  hit: jnp.ndarray  # (H, W) bool


def focal_length(cam: CameraConfig) -> float:
  """In pixels, from the vertical field of view."""
  return 0.5 * cam.height / np.tan(np.deg2rad(cam.fovy_deg) / 2)


def pixel_rays(cam: CameraConfig) -> np.ndarray:
  """(H, W, 3) unit ray directions in the camera frame (x right, y up, looking along -z)."""
  focal = focal_length(cam)
  u = (np.arange(cam.width) + 0.5 - cam.width / 2) / focal
  v = (np.arange(cam.height) + 0.5 - cam.height / 2) / focal
  uu, vv = np.meshgrid(u, v)
  rays = np.stack([uu, -vv, -np.ones_like(uu)], axis=-1)
  return (rays / np.linalg.norm(rays, axis=-1, keepdims=True)).astype(np.float32)


def geom_colors(env, state) -> jnp.ndarray:
  """(ngeom, 3) colour of every geom: objects from the state, the rest from the model."""
  slot = jnp.asarray(env.scene.index.geom_slot)
  base = jnp.asarray(env.scene.mj_model.geom_rgba[:, :3], jnp.float32)
  return jnp.where((slot >= 0)[:, None], state.color[jnp.maximum(slot, 0)], base)


def world_rays(mj_model: mujoco.MjModel, cams) -> tuple[np.ndarray, np.ndarray]:
  """(P, 3) origins and unit directions in the world of every pixel of every camera, in order."""
  data = mujoco.MjData(mj_model)
  mujoco.mj_kinematics(mj_model, data)
  mujoco.mj_camlight(mj_model, data)
  origins, directions = [], []
  for c, cam in enumerate(cams):
    rays = pixel_rays(cam).reshape(-1, 3).astype(np.float64) @ data.cam_xmat[c].reshape(3, 3).T
    directions.append(rays / np.linalg.norm(rays, axis=-1, keepdims=True))
    origins.append(np.broadcast_to(data.cam_xpos[c], rays.shape))
  return np.concatenate(origins), np.concatenate(directions)


def calibration(env, resolution: float) -> dict:
  """The simulator's cameras as `mvcoba_jax.deploy` reads a lab's calibration file, for
  heightmaps of `resolution` m: OpenCV intrinsics (pixel centres at integers), each camera's
  pose in the world (which is the workspace frame, so the base frame here), depth in metres."""
  data = mujoco.MjData(env.scene.mj_model)
  mujoco.mj_kinematics(env.scene.mj_model, data)
  mujoco.mj_camlight(env.scene.mj_model, data)
  config, cams = env.config, []
  for c, cam in enumerate(config.scene.cameras):
    pose = np.eye(4)  # OpenCV's camera axes: x right, y down, looking along +z
    pose[:3, :3] = data.cam_xmat[c].reshape(3, 3) @ np.diag([1.0, -1.0, -1.0])
    pose[:3, 3] = data.cam_xpos[c]
    f = focal_length(cam)
    cams.append({'name': f'cam{c}', 'width': cam.width, 'height': cam.height, 'fx': f, 'fy': f,
                 'cx': cam.width / 2 - 0.5, 'cy': cam.height / 2 - 0.5,
                 'camera_to_base': pose.tolist(), 'depth_scale': 1.0})
  return {'workspace': {'center': [0.0, 0.0, 0.0], 'yaw_deg': 0.0,
                        'half': config.scene.workspace_half, 'top': config.scene.workspace_top,
                        'resolution': resolution},
          'cameras': cams}


def render(env, state) -> tuple[CameraImage, ...]:
  """Every camera of the scene, for one environment (vmap over environments)."""
  cams = env.config.scene.cameras
  origins, directions = env.camera_rays
  dist, geom = env.backend.cast(state.sim, origins, directions)
  hit = dist >= 0
  dist = jnp.where(hit, dist, 0.0)
  colors = geom_colors(env, state)
  images, start = [], 0
  for cam in cams:
    shape = (cam.height, cam.width)
    sl = slice(start, start + cam.height * cam.width)
    start = sl.stop
    rays = pixel_rays(cam).reshape(-1, 3)
    d, g, h = dist[sl], geom[sl], hit[sl]
    images.append(CameraImage(
        depth=(d * -rays[:, 2]).reshape(shape),
        rgb=jnp.where(h[:, None], colors[jnp.maximum(g, 0)], 0.0).reshape(shape + (3,)),
        geom=jnp.where(h, g, -1).reshape(shape),
        points=(jnp.asarray(origins[sl], jnp.float32)
                + d[:, None] * jnp.asarray(directions[sl], jnp.float32)).reshape(shape + (3,)),
        hit=h.reshape(shape)))
  return tuple(images)
