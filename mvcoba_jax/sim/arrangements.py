"""Packed arrangements as a family: seeded generators of blocks set side by side with gaps the
fingers cannot enter, of seven types.

Each type is a function of a numpy Generator that returns its parts, (shape, dx, dy, yaw_deg,
dz): centres in the arrangement's own frame, `dz` the height of the part's underside (0 on the
table, else on the part below). `placed` centres the parts, turns them by a drawn angle and sets
them at a drawn spot inside the workspace. Training drops draw the `TRAINING` types
(`env.packed_share`: `tabletop.packed_bank`); validation cases draw the same types from other
seeds (`suites/generate.py`); the sealed packed suites add the `HELD_OUT` types, which no
training or validation draw holds.
"""
from __future__ import annotations

import numpy as np

from mvcoba_jax.sim import shapes

GAP = (0.0005, 0.008)  # m between neighbours: under the 1 cm of a finger's thickness
BOXES = ('cube', 'flat_box', 'tall_box', 'arch', 'prism')  # flat-sided shapes
SQUARE = ('cube', 'tall_box', 'disk', 'cylinder', 'octagon')  # footprints that tile a grid
LOW = ('cube', 'flat_box', 'disk', 'octagon')  # flat tops another block can rest on


def footprint(shape: str, yaw_deg: float = 0.0) -> np.ndarray:
  """(along x, along y) of the shape resting at a quarter-turn `yaw_deg`."""
  x, y, _ = shapes.shape(shape).rest_extent
  return np.array([y, x] if round(yaw_deg / 90) % 2 else [x, y], np.float64)


def height(shape: str) -> float:
  return float(shapes.shape(shape).rest_extent[2])


def row(rng, names, y: float, gap: float, turns: bool = True) -> tuple[list[tuple], float]:
  """`names` end to end along x from 0, each along the row or, with `turns`, turned across it
  (drawn), their centres half their depth above the line y; also the row's depth."""
  parts, cursor, depth = [], 0.0, 0.0
  for name in names:
    yaw = 90.0 * rng.integers(2) if turns else 0.0
    size = footprint(name, yaw)
    parts.append((name, cursor + 0.5 * size[0], y + 0.5 * size[1], yaw, 0.0))
    cursor, depth = cursor + size[0] + gap, max(depth, size[1])
  return parts, depth


def rows(rng) -> list[tuple]:
  """1-3 rows of flat-sided blocks end to end, each 10-20 cm long."""
  gap, parts, y = rng.uniform(*GAP), [], 0.0
  for _ in range(rng.integers(1, 4)):
    length, names = rng.uniform(0.10, 0.20), []
    while sum(footprint(n).max() for n in names) < length:
      names.append(BOXES[rng.integers(len(BOXES))])
    row_parts, depth = row(rng, names, y, gap)
    parts, y = parts + row_parts, y + depth + gap
  return parts


def grid(rng) -> list[tuple]:
  """2-4 x 2-4 of one shape whose footprint tiles a square grid."""
  shape, gap = SQUARE[rng.integers(len(SQUARE))], rng.uniform(*GAP)
  pitch = footprint(shape).max() + gap
  r, c = rng.integers(2, 5, size=2)
  return [(shape, i * pitch, j * pitch, 0.0, 0.0) for j in range(r) for i in range(c)]


def l_shape(rng) -> list[tuple]:
  """Two arms of 2-4 cubes or tall boxes meeting at a corner cube."""
  gap, arm = rng.uniform(*GAP), ('cube', 'tall_box')[rng.integers(2)]
  pitch = 0.05 + gap
  corner = [('cube', 0.0, 0.0, 0.0, 0.0)]
  along = [(arm, (i + 1) * pitch, 0.0, 0.0, 0.0) for i in range(rng.integers(2, 5))]
  up = [('cube', 0.0, (j + 1) * pitch, 0.0, 0.0) for j in range(rng.integers(2, 5))]
  return corner + along + up


def mixed(rng) -> list[tuple]:
  """2-3 rows of any shapes, round ones too, of mixed heights."""
  gap, parts, y = rng.uniform(*GAP), [], 0.0
  names_all = shapes.SHAPE_NAMES
  for _ in range(rng.integers(2, 4)):
    names = [names_all[i] for i in rng.integers(len(names_all), size=rng.integers(2, 5))]
    row_parts, depth = row(rng, names, y, gap)
    parts, y = parts + row_parts, y + depth + gap
  return parts


def ring(rng) -> list[tuple]:
  """A closed square frame of cubes, 3-4 a side, round its empty or filled middle."""
  gap, side = rng.uniform(*GAP), int(rng.integers(3, 5))
  pitch = 0.05 + gap
  cells = [(i, j) for i in range(side) for j in range(side)
           if i in (0, side - 1) or j in (0, side - 1)]
  if rng.integers(2):
    cells += [(i, j) for i in range(1, side - 1) for j in range(1, side - 1)][:1]
  name = ('cube', 'tall_box')[rng.integers(2)]
  return [(name if (i + j) % 2 else 'cube', i * pitch, j * pitch, 0.0, 0.0) for i, j in cells]


def t_shape(rng) -> list[tuple]:
  """A bar of 3-5 cubes with a stem of 2-3 flat boxes or cubes from its middle."""
  gap, n = rng.uniform(*GAP), int(rng.integers(3, 6))
  pitch = 0.05 + gap
  bar = [('cube', i * pitch, 0.0, 0.0, 0.0) for i in range(n)]
  stem_shape = ('cube', 'flat_box')[rng.integers(2)]
  length = footprint(stem_shape, 90.0)[1]
  mid = 0.5 * (n - 1) * pitch
  stem = [(stem_shape, mid, 0.025 + gap + (j + 0.5) * length + j * gap, 90.0, 0.0)
          for j in range(rng.integers(2, 4))]
  return bar + stem


def stack(rng) -> list[tuple]:
  """A row or 2 x 2-3 grid of low blocks, 2-4 of them carrying a second block, two high."""
  gap, base = rng.uniform(*GAP), LOW[rng.integers(len(LOW))]
  pitch = footprint(base).max() + gap
  r, c = int(rng.integers(1, 3)), int(rng.integers(2, 4))
  parts = [(base, i * pitch, j * pitch, 0.0, 0.0) for j in range(r) for i in range(c)]
  tops = rng.choice(len(parts), size=min(len(parts), int(rng.integers(2, 5))), replace=False)
  for k in sorted(tops):
    name = ('cube', 'disk', 'cylinder')[rng.integers(3)]
    parts.append((name, parts[k][1], parts[k][2], 0.0, height(base) + 0.001))
  return parts


TYPES = {'rows': rows, 'grid': grid, 'l_shape': l_shape, 'mixed': mixed, 'ring': ring,
         't_shape': t_shape, 'stack': stack}
TRAINING = ('rows', 'grid', 'l_shape', 'mixed')  # training and validation draw these
HELD_OUT = ('ring', 't_shape', 'stack')  # only the sealed packed suites hold these
MARGIN = 0.02  # m the arrangement's bounding circle keeps inside the workspace


def centred(parts: list[tuple]) -> tuple[list[tuple], float]:
  """`parts` moved so that their footprints' bounding box is centred on the origin, and the
  radius of the circle about it that holds every footprint."""
  corners = np.array([c for name, x, y, yaw, _ in parts
                      for c in ((x, y) - 0.5 * footprint(name, yaw),
                                (x, y) + 0.5 * footprint(name, yaw))])
  middle = 0.5 * (corners.min(axis=0) + corners.max(axis=0))
  radius = float(np.linalg.norm(corners - middle, axis=1).max())
  return [(n, x - middle[0], y - middle[1], yaw, dz) for n, x, y, yaw, dz in parts], radius


def placed(parts: list[tuple], rng, half: float) -> list[tuple]:
  """`parts` centred (`centred`), turned by a drawn yaw and set at a drawn spot whose bounding
  circle keeps `MARGIN` inside the workspace of half side `half`: (shape, x, y, yaw_deg, dz)."""
  parts, radius = centred(parts)
  angle = rng.uniform(0, 360)
  c, s = np.cos(np.radians(angle)), np.sin(np.radians(angle))
  room = max(half - MARGIN - radius, 0.0)
  centre = rng.uniform(-room, room, size=2)
  return [(name, centre[0] + c * dx - s * dy, centre[1] + s * dx + c * dy, (yaw + angle) % 360,
           dz) for name, dx, dy, yaw, dz in parts]
