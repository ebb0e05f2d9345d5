"""Two (or more) pinhole RGB-D cameras rendered by ray casting with `mjx.ray`, inside jit.

Each pixel's ray is cast against every geom (MJX has no acceleration structure), so the cost is
rays x geoms; the gripper bodies are excluded so it never hides the scene. Colour comes from the
hit geom: an object's colour lives in the environment state, so one compiled model serves any
colouring.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from flax import struct
from mujoco import mjx

from mvcoba_jax.config import CameraConfig

GRIPPER_BODIES = ('gripper', 'finger_left', 'finger_right')


@struct.dataclass
class CameraImage:
  """One camera's picture; pixels with no hit have hit False, geom -1 and depth 0."""
  depth: jnp.ndarray  # (H, W) distance along the optical axis (m)
  rgb: jnp.ndarray  # (H, W, 3) colour 0..1
  geom: jnp.ndarray  # (H, W) int32 id of the hit geom
  points: jnp.ndarray  # (H, W, 3) world coordinates of the hit
  hit: jnp.ndarray  # (H, W) bool


def pixel_rays(cam: CameraConfig) -> np.ndarray:
  """(H, W, 3) unit ray directions in the camera frame (x right, y up, looking along -z)."""
  focal = 0.5 * cam.height / np.tan(np.deg2rad(cam.fovy_deg) / 2)
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


def render(env, state) -> tuple[CameraImage, ...]:
  """Every camera of the scene, for one environment (vmap over environments)."""
  m = env.scene.mj_model
  exclude = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, b) for b in GRIPPER_BODIES]
  colors = geom_colors(env, state)
  images = []
  for c, cam in enumerate(env.config.scene.cameras):
    rays = pixel_rays(cam)
    rot = state.data.cam_xmat[c].reshape(3, 3)
    origin = state.data.cam_xpos[c]
    world = jnp.asarray(rays.reshape(-1, 3)) @ rot.T
    dist, geom = jax.vmap(lambda v: mjx.ray(env.model, state.data, origin, v,
                                            bodyexclude=exclude))(world)
    hit = dist >= 0
    dist = jnp.where(hit, dist, 0.0)
    shape = rays.shape[:2]
    images.append(CameraImage(
        depth=(dist * -rays[..., 2].reshape(-1)).reshape(shape),
        rgb=jnp.where(hit[:, None], colors[jnp.maximum(geom, 0)], 0.0).reshape(shape + (3,)),
        geom=jnp.where(hit, geom, -1).reshape(shape),
        points=(origin + dist[:, None] * world).reshape(shape + (3,)),
        hit=hit.reshape(shape)))
  return tuple(images)
