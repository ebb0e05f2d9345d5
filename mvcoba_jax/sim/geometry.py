"""The one place for frames and rotations.

Pixel (row, col) of a heightmap <-> world (x, y): row grows with y, col grows with x
(`contract.pixel_to_world`, the robot's contract, gives a cell's centre). Rotation index k means
the angle k * 2 * pi / num_rotations.
"""
from __future__ import annotations

import jax.numpy as jnp
import mujoco
import numpy as np


def rotation_angle(k, num_rotations: int = 16):
  """Angle (rad) of rotation index k: the primitive's yaw and push direction."""
  return k * (2.0 * jnp.pi / num_rotations)


def yaw_quat(yaw):
  """Quaternion (w, x, y, z) of a rotation by `yaw` about the world z axis."""
  half = 0.5 * yaw
  zero = jnp.zeros_like(half)
  return jnp.stack([jnp.cos(half), zero, zero, jnp.sin(half)], axis=-1)


def quat_mul(a, b):
  """Hamilton product of (w, x, y, z) quaternions (broadcasts)."""
  aw, ax, ay, az = jnp.moveaxis(a, -1, 0)
  bw, bx, by, bz = jnp.moveaxis(b, -1, 0)
  return jnp.stack([
      aw * bw - ax * bx - ay * by - az * bz,
      aw * bx + ax * bw + ay * bz - az * by,
      aw * by - ax * bz + ay * bw + az * bx,
      aw * bz + ax * by - ay * bx + az * bw,
  ], axis=-1)


def in_frame(quat, v):
  """Vectors `v` (..., 3) of the world in the frame that unit quaternions `quat` (..., 4) turn
  the world's axes to: conj(quat) v quat."""
  conj = quat * jnp.asarray([1.0, -1.0, -1.0, -1.0], quat.dtype)
  pure = jnp.concatenate([jnp.zeros_like(v[..., :1]), v], axis=-1)
  return quat_mul(quat_mul(conj, pure), quat)[..., 1:]


def euler_xyz_matrix(a: float, b: float, c: float) -> np.ndarray:
  """R = Rx(a) Ry(b) Rz(c) as a 3x3 numpy matrix (the convention of VPG's test cases)."""
  ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
  rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
  ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
  rz = np.array([[cc, -sc, 0], [sc, cc, 0], [0, 0, 1]])
  return rx @ ry @ rz


def matrix_to_quat(m: np.ndarray) -> np.ndarray:
  """(w, x, y, z) unit quaternion of a rotation matrix (numpy, host side)."""
  q = np.empty(4)
  mujoco.mju_mat2Quat(q, np.asarray(m, dtype=np.float64).reshape(9))
  return q


def rotate_images(images, angle):
  """`images` (N, H, W, C) rotated by `angle` (scalar or (N,) rad) about the image centre.

  Counter-clockwise in the pixel frame (x = col, y = row), the frame of `contract.pixel_to_world`,
  so a world direction at yaw t points at yaw t + angle afterwards: content at (x, y) relative to
  the centre moves to (x cos a - y sin a, x sin a + y cos a). Each output pixel samples its source
  bilinearly; sources outside the image read 0 (a missing cell). Linear in `images`, smooth in
  `angle`: the networks rotate inputs by -angle and outputs back by +angle with it.
  """
  n, h, w, _ = images.shape
  angle = jnp.broadcast_to(jnp.asarray(angle, images.dtype), (n,))
  cy, cx = 0.5 * (h - 1), 0.5 * (w - 1)
  y, x = jnp.meshgrid(jnp.arange(h, dtype=images.dtype) - cy,
                      jnp.arange(w, dtype=images.dtype) - cx, indexing='ij')
  cos, sin = jnp.cos(angle)[:, None, None], jnp.sin(angle)[:, None, None]
  src_row = cy - sin * x + cos * y  # the inverse rotation of each output pixel
  src_col = cx + cos * x + sin * y
  row0, col0 = jnp.floor(src_row), jnp.floor(src_col)
  frac_row, frac_col = src_row - row0, src_col - col0
  row0, col0 = row0.astype(jnp.int32), col0.astype(jnp.int32)
  batch = jnp.arange(n)[:, None, None]
  out = jnp.zeros_like(images)
  for dr, dc in ((0, 0), (0, 1), (1, 0), (1, 1)):
    r, c = row0 + dr, col0 + dc
    weight = (frac_row if dr else 1 - frac_row) * (frac_col if dc else 1 - frac_col)
    weight = jnp.where((r >= 0) & (r < h) & (c >= 0) & (c < w), weight, 0.0)
    out = out + weight[..., None] * images[batch, jnp.clip(r, 0, h - 1), jnp.clip(c, 0, w - 1)]
  return out
