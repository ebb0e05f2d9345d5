"""CPG's suppression of actions that cannot act, as factors on whole Q maps.

Collaborative Pushing-Grasping (public code `nizhihao/Collaborative-Pushing-Grasping`,
`utils.policynms_push/grasp` and the action masks of `main.py`) scores a grasp by the share of
its fingers' landing zones that is free, a push by the share of the strip ahead of it that is
occupied, allows pushes only from a ring 1-2.5 cm off the objects' edges and multiplies the
predictions (+0.1) by these. Here every (rotation, cell) gets its factor, in the frame where the
rotation's push points along +col and the fingers lie along the rows (as the networks see it),
from box sums of the occupancy; the factor maps are turned back like Q maps.

Departures: CPG factors only the best cell of each rotation and, when all of those are
suppressed, falls back to the raw maximum; here every cell is factored, so a suppressed cell is
never chosen while any cell is allowed (the raw maps decide only when none is). CPG allows grasps
at the centre of each object blob (contours of its mask); here at any cell where something
stands. Zones are in metres, scaled to this gripper where CPG's were its own.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp

from mvcoba_jax.learner.networks import NO_ACTION
from mvcoba_jax.sim.geometry import rotate_images, rotation_angle
from mvcoba_jax.sim.config import GripperConfig

OBJECT_HEIGHT = 0.013  # m: a cell holds an object above this (CPG: 0.618 - 0.605 m)
PUSH_RING = (0.0105, 0.0245)  # m from an object's edge (CPG: 7 and 15 px dilations at 3.5 mm)
PUSH_AHEAD = (0.0385, 0.070, 0.014)  # m: strip ahead of a push, from, to, half width (11-20 px)
ZONE_MARGIN = 0.005  # m the landing zones reach beyond the fingers, inward and to either side


def finger_zone(gripper: GripperConfig) -> tuple[float, float, float]:
  """Where the gripper's open fingers land, m from the grasp's centre along the closing line:
  from ZONE_MARGIN inside the opening to the fingers' outer faces, and ZONE_MARGIN beyond the
  fingers' width either side (CPG: 10-16 px, +-6 px, for its Robotiq's)."""
  half = gripper.max_opening / 2
  return (half - ZONE_MARGIN, half + gripper.finger_thickness,
          gripper.finger_width / 2 + ZONE_MARGIN)
Q_OFFSET = 0.1  # CPG adds it to the predictions before weighting


def _cells(metres: float, resolution: float) -> int:
  return int(round(metres / resolution))


def _box_share(x, rows: tuple[int, int], cols: tuple[int, int]):
  """Mean of x (N, R, R) over each cell's window [r + rows[0], r + rows[1]] x [c + cols[0],
  c + cols[1]] (inclusive); outside the map counts as empty."""
  m = max(abs(v) for v in rows + cols)
  h, w = rows[1] - rows[0] + 1, cols[1] - cols[0] + 1
  sums = jax.lax.reduce_window(x, 0.0, jax.lax.add, (1, h, w), (1, 1, 1),
                               ((0, 0), (m, m), (m, m)))
  side = x.shape[1]
  r0, c0 = rows[0] + m, cols[0] + m
  return sums[:, r0:r0 + side, c0:c0 + side] / (h * w)


def _dilate(x, radius: int):
  """Square dilation of x (N, R, R) by `radius` cells."""
  size = 2 * radius + 1
  return jax.lax.reduce_window(x, -jnp.inf, jax.lax.max, (1, size, size), (1, 1, 1), 'SAME')


def factors(height, num_rotations: int, resolution: float, push_room: float = 0.0,
            gripper: GripperConfig = GripperConfig()):
  """(B, 2, K, R, R) factors in [0, 1] (PUSH, GRASP) of every rotation and cell, from the
  surface height (B, R, R) the method sees; 0 suppresses. With `push_room` (m), also every push
  whose start has less room than that to the workspace's border along its direction."""
  b, side, _ = height.shape
  occupied = (height > OBJECT_HEIGHT).astype(jnp.float32)
  angle = rotation_angle(jnp.arange(num_rotations), num_rotations)
  turned = rotate_images(jnp.repeat(occupied, num_rotations, axis=0)[..., None],
                         -jnp.tile(angle, b))[..., 0]  # (B*K, R, R)
  ahead = (_cells(PUSH_AHEAD[0], resolution), _cells(PUSH_AHEAD[1], resolution))
  across = _cells(PUSH_AHEAD[2], resolution)
  push = _box_share(turned, (-across, across), ahead)
  zone = finger_zone(gripper)
  inner, outer = _cells(zone[0], resolution), _cells(zone[1], resolution)
  width = _cells(zone[2], resolution)
  fingers = jnp.maximum(_box_share(turned, (inner, outer), (-width, width)),
                        _box_share(turned, (-outer, -inner), (-width, width)))
  maps = jnp.stack([push, 1.0 - fingers], axis=-1)  # (B*K, R, R, 2)
  maps = rotate_images(maps, jnp.tile(angle, b)).reshape(b, num_rotations, side, side, 2)
  ring = (_dilate(occupied, _cells(PUSH_RING[1], resolution))
          * (1.0 - _dilate(occupied, _cells(PUSH_RING[0], resolution))))
  masks = jnp.stack([ring, occupied], axis=1)[:, :, None]  # (B, 2, 1, R, R)
  f = jnp.clip(jnp.moveaxis(maps, -1, 1), 0.0, 1.0) * masks
  if not push_room:
    return f
  room = (room_ahead(side, num_rotations, resolution) >= push_room).astype(f.dtype)
  return jnp.stack([f[:, 0] * room, f[:, 1]], axis=1)  # (PUSH, GRASP)


def room_ahead(side: int, num_rotations: int, resolution: float):
  """(K, R, R) distance (m) from each cell's centre to the square workspace's border along each
  rotation's push direction (counter-clockwise from +col towards +row)."""
  half = side * resolution / 2
  centre = -half + (jnp.arange(side) + 0.5) * resolution
  angle = rotation_angle(jnp.arange(num_rotations), num_rotations)[:, None, None]
  x, y = centre[None, None, :], centre[None, :, None]

  def along(position, step):  # distance to the border on one axis; inf when not moving on it
    moving = jnp.abs(step) > 1e-9
    target = jnp.where(step > 0, half, -half)
    return jnp.where(moving, (target - position) / jnp.where(moving, step, 1.0), jnp.inf)
  return jnp.minimum(along(x, jnp.cos(angle)), along(y, jnp.sin(angle)))


def scores(q, height, resolution: float, per_primitive: bool = False, push_room: float = 0.0,
           gripper: GripperConfig = GripperConfig()):
  """The maps CPG's rule compares: (Q + 0.1) x factor where the factor allows, NO_ACTION where
  it suppresses; for a state with no allowed action at all, its raw Q maps (with
  `per_primitive`, for a rule that is given its primitive: a primitive with no allowed action
  keeps its raw Q map). `q` (B, 2, K, R, R) holds every rotation in order; `push_room`:
  `factors`'."""
  f = factors(height, q.shape[2], resolution, push_room, gripper)
  allowed = f > 0
  weighted = jnp.where(allowed, (q + Q_OFFSET) * f, NO_ACTION)
  anything = jnp.any(allowed, axis=(2, 3, 4) if per_primitive else (1, 2, 3, 4), keepdims=True)
  return jnp.where(anything, weighted, q)
