"""Where occluders stand: the regions of occluder poses that training (`env.occluded_share`), the
validation cases and the shipped test cases each draw from, kept apart so that no policy is
tested or validated under an occluder pose it trained with.

A pose is given in the frame of the camera the occluder hides: `along`, the fraction of the
camera's horizontal distance from the workspace centre towards the camera; `side`, sideways (m,
positive a quarter turn anticlockwise from the camera's direction); `height` of the centre (m); `yaw`,
the turn (deg) from facing the camera. The slot gives the size: slot 0 (24 x 24 cm) hides all or
most of the workspace, slots 1 and 2 (10 x 10 cm) a part.

| region | height (m) | abs(yaw) (deg) | along: whole / part | side (m): whole / abs, part |
|---|---|---|---|---|
| training | 0.53-0.60 | 23-40 | 0.78-0.92 / 0.72-0.86 | -0.04-0.04 / 0.00-0.05 |
| test | 0.45-0.50 | 0-8 | 0.78-0.92 / 0.72-0.86 | -0.04-0.04 / 0.00-0.05 |
| validation | 0.37-0.42 | 0-8 | 0.78-0.92 / 0.72-0.86 | -0.04-0.04 / 0.00-0.05 |
| validation, high | 0.63-0.66 | 0-8 | 0.78-0.92 / 0.72-0.86 | -0.04-0.04 / 0.00-0.05 |

Every training pose is at least `MARGIN_M` away in height and `MARGIN_DEG` in yaw from every test
pose: both margins at once (tests/unit/test_occluders.py checks draws against every occluder of
the shipped suites). Validation poses are as far from training's in both, and `MARGIN_M` in
height from the test's. The validation region hides little (its occluders stand low, below most
of a camera's rays); the high one, above training's and near the cameras' height, hides as much
as the test's, for a validation occluded suite as hard as the test's.
A box is symmetric under a half turn, so yaws compare modulo 180 degrees.
"""
from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

MARGIN_M = 0.03
MARGIN_DEG = 15.0


@dataclasses.dataclass(frozen=True)
class Region:
  """A box of occluder poses in the hidden camera's frame (see the module's table)."""
  height: tuple[float, float]
  yaw: tuple[float, float]  # abs(yaw), either sign drawn
  along_whole: tuple[float, float] = (0.78, 0.92)
  along_part: tuple[float, float] = (0.72, 0.86)
  side_whole: tuple[float, float] = (-0.04, 0.04)
  side_part: tuple[float, float] = (0.0, 0.05)  # abs(side), either sign drawn


TRAINING = Region(height=(0.53, 0.60), yaw=(23.0, 40.0))
TEST = Region(height=(0.45, 0.50), yaw=(0.0, 8.0))
VALIDATION = Region(height=(0.37, 0.42), yaw=(0.0, 8.0))
VALIDATION_HIGH = Region(height=(0.63, 0.66), yaw=(0.0, 8.0))


def pose(region: Region, camera_xy, part, u):
  """World (x, y, z, yaw_rad) of an occluder before the camera at `camera_xy`: whole (slot 0) or
  `part` (a partial slot), from `u`, six uniform variates in [0, 1) (jax or numpy)."""
  lerp = lambda bounds, v: bounds[0] + (bounds[1] - bounds[0]) * v
  sign = lambda v: jnp.where(v < 0.5, -1.0, 1.0)
  along = jnp.where(part, lerp(region.along_part, u[0]), lerp(region.along_whole, u[0]))
  side = jnp.where(part, sign(u[1]) * lerp(region.side_part, u[2]), lerp(region.side_whole, u[2]))
  height = lerp(region.height, u[3])
  yaw = jnp.radians(sign(u[4]) * lerp(region.yaw, u[5]))
  azimuth = jnp.arctan2(camera_xy[1], camera_xy[0])
  c, s = jnp.cos(azimuth), jnp.sin(azimuth)
  along = along * jnp.hypot(camera_xy[0], camera_xy[1])
  return (c * along - s * side, s * along + c * side, height, azimuth + yaw)


def drawn(region: Region, key, cameras_xy, partial_slot: bool):
  """(camera index, part, (x, y, z, yaw)) of one occluder drawn from `region`: the camera it
  hides uniform, whole or part equally often when a partial slot exists (else whole)."""
  k_camera, k_part, k_u = jax.random.split(key, 3)
  camera = jax.random.randint(k_camera, (), 0, cameras_xy.shape[0])
  part = jax.random.bernoulli(k_part) if partial_slot else jnp.bool_(False)
  return camera, part, pose(region, cameras_xy[camera], part, jax.random.uniform(k_u, (6,)))


def separation(a, b):
  """(distances (n, m) between the centres in m, turns (n, m) between the yaws in degrees modulo
  a half turn) of occluder poses `a` (n, 4) and `b` (m, 4), each (x, y, z, yaw_rad)."""
  a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
  distance = np.linalg.norm(a[:, None, :3] - b[None, :, :3], axis=-1)
  turn = np.abs((np.degrees(a[:, None, 3] - b[None, :, 3]) + 90.0) % 180.0 - 90.0)
  return distance, turn
