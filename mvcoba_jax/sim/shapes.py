"""Shapes: the VPG block set, built procedurally in each block's VPG mesh frame, and objects from
mesh files (`meshes`).

Every block is described in the frame of VPG's mesh file (origin at the bounding-box centre), so
the Euler angles of VPG's test cases apply to our bodies unchanged. Curved shapes are convex
polygonal prisms (MJX has no cylinder-box collision); the concave arch is three boxes. Any other
name is a mesh reference (`mug.obj`, `scans/mug/`, `mug.stl@0.001`): `shape` reads it once.
"""
from __future__ import annotations

import dataclasses
import functools
import os
import pathlib

import mujoco
import numpy as np

from mvcoba_jax.sim import meshes

# VPG's ten block colours (RGB 0..1), in VPG's order.
COLORS = np.array([
    [78, 121, 167], [89, 161, 79], [156, 117, 95], [242, 142, 43], [237, 201, 72],
    [186, 176, 172], [255, 87, 89], [176, 122, 161], [118, 183, 178], [255, 157, 167],
], dtype=np.float32) / 255.0

CYLINDER_SIDES = 12


@dataclasses.dataclass(frozen=True)
class Part:
  """One collision geom of a shape: a box (half sizes) or a convex mesh (its hull's vertices)."""
  kind: str  # 'box' | 'mesh'
  pos: tuple[float, float, float] = (0.0, 0.0, 0.0)
  half_size: tuple[float, float, float] | None = None
  vertices: tuple[tuple[float, float, float], ...] | None = None


@dataclasses.dataclass(frozen=True)
class Shape:
  name: str
  vpg_file: str | None  # the block's mesh file in VPG's cases; None for mesh objects
  extent: tuple[float, float, float]  # axis-aligned size in the mesh frame (m)
  parts: tuple[Part, ...]
  # Orientation (w, x, y, z) in which random drops place the shape, before their random yaw.
  rest_quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)

  @property
  def rest_extent(self) -> np.ndarray:
    """Axis-aligned size when resting in `rest_quat` (quarter turns only)."""
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, np.asarray(self.rest_quat, float))
    return np.abs(rot.reshape(3, 3)) @ np.asarray(self.extent)


def _prism_vertices(polygon_2d: np.ndarray, axis: int, length: float) -> np.ndarray:
  """Vertices of a right prism: a 2-D polygon in the plane normal to `axis`, extruded along it."""
  other = [i for i in range(3) if i != axis]
  verts = []
  for side in (-0.5, 0.5):
    for u, v in polygon_2d:
      p = np.zeros(3)
      p[other[0]], p[other[1]], p[axis] = u, v, side * length
      verts.append(p)
  return np.array(verts)


def _regular_polygon(n: int, across_flats: float, phase: float) -> np.ndarray:
  circumradius = 0.5 * across_flats / np.cos(np.pi / n)
  ang = phase + 2 * np.pi * np.arange(n) / n
  return np.stack([circumradius * np.cos(ang), circumradius * np.sin(ang)], axis=1)


def _mesh(vertices: np.ndarray) -> Part:
  return Part('mesh', vertices=tuple(tuple(float(c) for c in v) for v in vertices))


def _block_meshes() -> dict[str, Part]:
  """The blocks' convex meshes, keyed by block name."""
  tri = np.array([[-0.0933 / 2, -0.0486 / 2], [0.0933 / 2, -0.0486 / 2], [0.0, 0.0486 / 2]])
  # Triangle is in the x-z plane: (u, v) = (x, z), extruded along y.
  prism = _prism_vertices(tri, axis=1, length=0.05)
  # Round prisms: flats aligned with the frame axes so the stated extents hold.
  n = CYLINDER_SIDES
  cylinder = _prism_vertices(_regular_polygon(n, 0.0448, np.pi / n), axis=2, length=0.05)
  disk = _prism_vertices(_regular_polygon(n, 0.050, np.pi / n), axis=2, length=0.025)
  octagon = _prism_vertices(_regular_polygon(8, 0.0605, np.pi / 8), axis=0, length=0.025)
  return {'prism': _mesh(prism), 'cylinder': _mesh(cylinder), 'disk': _mesh(disk),
          'octagon': _mesh(octagon)}


def _box(hx, hy, hz, pos=(0.0, 0.0, 0.0)) -> Part:
  return Part('box', pos=pos, half_size=(hx, hy, hz))


_MESHES = _block_meshes()
SHAPES: dict[str, Shape] = {s.name: s for s in [
    Shape('prism', '0.obj', (0.0933, 0.050, 0.0486), (_MESHES['prism'],)),
    # Arch: two 2.5 cm legs and a 2.5 cm thick top span; the half-round cut-out is approximated
    # by a 5 x 2.5 cm rectangular opening.
    Shape('arch', '1.obj', (0.100, 0.050, 0.050), (
        _box(0.0125, 0.025, 0.025, (-0.0375, 0.0, 0.0)),
        _box(0.0125, 0.025, 0.025, (0.0375, 0.0, 0.0)),
        _box(0.025, 0.025, 0.0125, (0.0, 0.0, 0.0125)),
    )),
    # Dropped lying on an octagonal face (axis vertical): a quarter turn about y.
    Shape('octagon', '2.obj', (0.025, 0.0605, 0.0605), (_MESHES['octagon'],),
          rest_quat=(np.sqrt(0.5), 0.0, np.sqrt(0.5), 0.0)),
    Shape('flat_box', '3.obj', (0.100, 0.050, 0.025), (_box(0.05, 0.025, 0.0125),)),
    Shape('cube', '4.obj', (0.050, 0.050, 0.050), (_box(0.025, 0.025, 0.025),)),
    Shape('tall_box', '6.obj', (0.050, 0.050, 0.100), (_box(0.025, 0.025, 0.05),)),
    Shape('disk', '7.obj', (0.050, 0.050, 0.025), (_MESHES['disk'],)),
    Shape('cylinder', '8.obj', (0.0448, 0.0448, 0.050), (_MESHES['cylinder'],)),
]}

SHAPE_NAMES = tuple(SHAPES)


def reference(text: str, base: pathlib.Path | None = None) -> str:
  """The shape name `text` stands for: a block's name, else the absolute mesh reference (a path
  relative to `base`, else to the working folder). A bare word that is neither is refused."""
  if text in SHAPES:
    return text
  absolute = meshes.absolute(text, base)
  if not any(c in text for c in '/.@') and not os.path.exists(absolute):
    raise meshes.MeshError(f'unknown shape {text!r}; known: {", ".join(SHAPE_NAMES)}, or a '
                           'mesh file or folder')
  return absolute


@functools.lru_cache(maxsize=256)
def shape(name: str) -> Shape:
  """The block of that name, else the object the mesh reference names (meshes.MeshError if it
  cannot be one)."""
  if name in SHAPES:
    return SHAPES[name]
  parts = tuple(_mesh(v) for v in meshes.parts(name))
  every = np.concatenate([np.asarray(p.vertices) for p in parts])
  extent = tuple(float(e) for e in every.max(0) - every.min(0))
  return Shape(name, None, extent, parts)
# Block tables: the shape each mesh file name of a VPG-format case file stands for. Files written by
# other simulators number their blocks differently; a table is chosen per suite (`--blocks`).
# 'mvcoba': the MV-COBA authors' block set, whose 0.obj is the short polygonal prism (VPG's 2.obj,
# axis along x) and 1.obj the 5 cm cube (VPG's 4.obj); 7.obj is taken as VPG's disk.
# Another table is one more entry here (`add_block_table`).
BLOCK_TABLES = {
    'vpg': {s.vpg_file: s.name for s in SHAPES.values()},
    'mvcoba': {'0.obj': 'octagon', '1.obj': 'cube', '2.obj': 'octagon', '3.obj': 'flat_box',
               '4.obj': 'cube', '6.obj': 'tall_box', '7.obj': 'disk', '8.obj': 'cylinder'},
}


def add_block_table(name: str, table: dict[str, str]) -> None:
  """Registers a block table: mesh file name -> one of SHAPE_NAMES or a mesh reference (made
  absolute here, relative to the working folder)."""
  table = {k: reference(v) for k, v in table.items()}
  for name_or_path in table.values():
    shape(name_or_path)  # a mesh that cannot be an object is refused now, not when a case loads
  BLOCK_TABLES[name] = table


def pool_record(pool) -> list[dict]:
  """What a policy records of the objects it trained on: each pool entry's name, its count and,
  for a mesh object, the SHA-256 of its files (`meshes.content_hash`)."""
  return [{'shape': name, 'slots': count} if name in SHAPES else
          {'shape': name, 'slots': count, 'sha256': meshes.content_hash(name)}
          for name, count in pool]


def footprint_radius(name: str) -> float:
  """Radius of the circle that bounds the shape's footprint when resting in `rest_quat`."""
  ex, ey, _ = shape(name).rest_extent
  return 0.5 * float(np.hypot(ex, ey))
