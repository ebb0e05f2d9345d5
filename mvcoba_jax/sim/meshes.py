"""Objects from mesh files: the convex parts that MuJoCo, MJX and Warp collide, from a file or a
folder of parts.

MuJoCo collides a mesh geom as the convex hull of its vertices, so an object is a set of convex
parts: a convex file is one; a folder holds one object's parts already split (as Google Scanned
Objects' `model_collision_*.obj`); any other file is split by CoACD, whose parts are cached by the
file's content hash beside the compilation cache, so a second run does not split it again. Each
part keeps at most MAX_PART_VERTICES hull vertices (MJX's convex collision does work per vertex
and face). The object's frame is its bounding box's centre, as the blocks' (VPG's mesh frame).

A reference is a path with an optional scale: `mug.obj`, `scans/mug.stl@0.001` (millimetres).
Units are metres after the scale. The shipped object sets are named inside the package,
`package:sim/objects/everyday/mug`, so saved configs do not depend on where it is installed.
"""
from __future__ import annotations

import functools
import hashlib
import os
import pathlib

import numpy as np
from scipy import spatial

from mvcoba_jax.sim.errors import Error

SUFFIXES = ('.obj', '.stl', '.ply', '.glb', '.gltf', '.off')
MAX_FILE_BYTES = 200_000_000
MAX_FACES = 500_000  # a file's triangles: a scan's visual mesh fits, a point cloud does not
MAX_PARTS = 16  # convex parts of one object: each is a collision geom of every object slot
MAX_PART_VERTICES = 64
MIN_SIZE = 0.01  # m: the smallest object's largest side (the cameras' pixel is ~4 mm)
MAX_SIZE = 1.0  # m: beyond this a file is most likely in millimetres (`path@0.001`)
# CoACD's parameters (its defaults, the hull count and vertices capped as above); changing them
# changes the cache key. A decomposition of one's own is a folder of parts.
COACD = {'threshold': 0.05, 'max_convex_hull': MAX_PARTS, 'preprocess_resolution': 50,
         'mcts_iterations': 150, 'max_ch_vertex': MAX_PART_VERTICES, 'seed': 0}
CACHE_VERSION = 1
PACKAGE = pathlib.Path(__file__).resolve().parents[1]  # mvcoba_jax/
IN_PACKAGE = 'package:'  # how a reference names a file inside it


class MeshError(Error):
  """A mesh reference that cannot be an object; the message names the file and what is wrong."""


def cache_folder() -> pathlib.Path:
  """Where split meshes are kept: beside the compilation cache ($MVCOBA_JAX_CACHE's parent,
  else ~/.cache/mvcoba-jax)."""
  jax_cache = os.environ.get('MVCOBA_JAX_CACHE')
  root = pathlib.Path(jax_cache).parent if jax_cache else pathlib.Path.home() / '.cache' / (
      'mvcoba-jax')
  return root / 'meshes'


def _located(path: str) -> pathlib.Path:
  """A reference's path as a file: `package:` ones inside the installed package."""
  return PACKAGE / path[len(IN_PACKAGE):] if path.startswith(IN_PACKAGE) else pathlib.Path(path)


def split_reference(reference: str) -> tuple[pathlib.Path, float]:
  """The path and scale of `path[@scale]`."""
  path, at, scale_text = reference.rpartition('@')
  if not at:
    return _located(reference), 1.0
  try:
    scale = float(scale_text)
  except ValueError:
    raise MeshError(f'{reference}: scale {scale_text!r} after @ is not a number') from None
  if not 0.0 < scale < 1e6:
    raise MeshError(f'{reference}: scale {scale_text} must be positive')
  return _located(path), scale


def absolute(reference: str, base: pathlib.Path | None = None) -> str:
  """`reference` with its path made absolute (relative to `base`, else the working folder); a
  file inside the package (the shipped object sets) is named `package:PATH`, so a config that
  trained on it reads the same wherever the package is installed."""
  path, _ = split_reference(reference)  # the scale checked, and kept as written
  full = os.path.abspath(pathlib.Path(base or '.') / path)
  if pathlib.Path(full).is_relative_to(PACKAGE):
    full = IN_PACKAGE + pathlib.Path(full).relative_to(PACKAGE).as_posix()
  _, at, scale = reference.rpartition('@')
  return full + (at + scale if at else '')


def _read(path: pathlib.Path):
  """The triangle mesh of one file (a scene's geometries concatenated)."""
  import trimesh  # pylint: disable=import-outside-toplevel  (only mesh objects need it)
  if path.suffix.lower() not in SUFFIXES:
    raise MeshError(f'{path}: not a mesh file (expected {", ".join(SUFFIXES)})')
  try:
    size = path.stat().st_size
  except OSError as e:
    raise MeshError(f'{path}: cannot read the mesh: {e.strerror}') from None
  if size > MAX_FILE_BYTES:
    raise MeshError(f'{path}: {size} bytes; a mesh file holds at most {MAX_FILE_BYTES}')
  try:
    loaded = trimesh.load(path, force='mesh')
  except Exception as e:  # trimesh raises what its format readers raise
    raise MeshError(f'{path}: not a readable mesh ({type(e).__name__}: '
                    f'{str(e).splitlines()[0][:120] if str(e) else "no detail"})') from None
  if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
    raise MeshError(f'{path}: the file holds no triangles')
  if len(loaded.faces) > MAX_FACES:
    raise MeshError(f'{path}: {len(loaded.faces)} faces; a mesh holds at most {MAX_FACES} '
                    '(decimate it, or give a folder of convex parts)')
  if not np.all(np.isfinite(loaded.vertices)):
    raise MeshError(f'{path}: vertices that are not finite numbers')
  return loaded


def _convex_hull(vertices: np.ndarray, where):
  """scipy's hull of a point set; MeshError if the points span no volume."""
  try:
    hull = spatial.ConvexHull(vertices)
  except (spatial.QhullError, ValueError):
    hull = None
  if hull is None or hull.volume < 1e-15:
    raise MeshError(f'{where}: degenerate: its points span no volume (flat, a line or a point)')
  return hull


def _hull(vertices: np.ndarray, where: str) -> np.ndarray:
  """The hull vertices of a point set, at most MAX_PART_VERTICES of them (farthest-point
  sampling, which keeps the extremes); MeshError if the points span no volume."""
  points = vertices[_convex_hull(vertices, where).vertices]
  if len(points) <= MAX_PART_VERTICES:
    return points
  chosen = [int(np.argmax(np.linalg.norm(points - points.mean(0), axis=1)))]
  dist = np.linalg.norm(points - points[chosen[0]], axis=1)
  while len(chosen) < MAX_PART_VERTICES:
    chosen.append(int(np.argmax(dist)))
    dist = np.minimum(dist, np.linalg.norm(points - points[chosen[-1]], axis=1))
  return points[np.sort(chosen)]


def _split(path: pathlib.Path, mesh) -> list[np.ndarray]:
  """CoACD's convex parts of a non-convex mesh, read from or written to the cache."""
  import coacd  # pylint: disable=import-outside-toplevel
  digest = hashlib.sha256(path.read_bytes())
  digest.update(repr((sorted(COACD.items()), CACHE_VERSION)).encode())
  cached = cache_folder() / f'{digest.hexdigest()}.npz'
  if cached.exists():
    with np.load(cached) as saved:
      return [saved[f'part{i}'] for i in range(len(saved.files))]
  coacd.set_log_level('error')
  try:
    parts = coacd.run_coacd(coacd.Mesh(np.asarray(mesh.vertices), np.asarray(mesh.faces)),
                            **COACD)
  except Exception as e:  # CoACD raises what its C++ core raises
    raise MeshError(f'{path}: CoACD cannot split it ({type(e).__name__}: {str(e)[:120]}); give a '
                    'folder of convex parts instead') from None
  vertices = [np.asarray(v, np.float64) for v, _ in parts]
  partial = cached.with_suffix(f'.{os.getpid()}.npz')
  try:
    cached.parent.mkdir(parents=True, exist_ok=True)
    np.savez(partial, **{f'part{i}': v for i, v in enumerate(vertices)})
    os.replace(partial, cached)  # whole or absent: a killed run leaves no half file
  except OSError:  # a cache that cannot be written costs the next run the split, nothing else
    partial.unlink(missing_ok=True)
  return vertices


def _file_parts(path: pathlib.Path) -> list[np.ndarray]:
  """One part for a closed mesh that fills its hull (convex but for rounding), else CoACD's."""
  mesh = _read(path)
  vertices = np.asarray(mesh.vertices, np.float64)
  hull_volume = _convex_hull(vertices, path).volume  # a flat file is refused before CoACD
  if mesh.is_watertight and abs(mesh.volume) >= 0.98 * hull_volume:
    return [vertices]
  return _split(path, mesh)


def _folder_parts(path: pathlib.Path) -> list[np.ndarray]:
  files = sorted(p for p in path.iterdir() if p.suffix.lower() in SUFFIXES)
  collision = [p for p in files if p.stem.startswith('model_collision')]
  files = collision or files
  if not files:
    raise MeshError(f'{path}: a folder without parts (no {", ".join(SUFFIXES)} files)')
  return [np.asarray(_read(p).vertices) for p in files]


@functools.lru_cache(maxsize=256)
def parts(reference: str) -> tuple[np.ndarray, ...]:
  """The convex parts (vertices, metres, the bounding box's centre at the origin) of the object
  a reference names."""
  path, scale = split_reference(reference)
  if path.is_dir():
    raw = _folder_parts(path)
  elif path.exists():
    raw = _file_parts(path)
  else:
    raise MeshError(f'{path}: no such mesh file or folder')
  if len(raw) > MAX_PARTS:
    raise MeshError(f'{path}: {len(raw)} convex parts; an object holds at most {MAX_PARTS}')
  hulls = [_hull(scale * np.asarray(v, np.float64), f'{path} (part {i})')
           for i, v in enumerate(raw)]
  every = np.concatenate(hulls)
  low, high = every.min(0), every.max(0)
  size = float((high - low).max())
  if size < MIN_SIZE:
    raise MeshError(f'{reference}: {1000 * size:.1f} mm across; an object is at least '
                    f'{1000 * MIN_SIZE:g} mm (a file in other units takes a scale: path@0.001)')
  if size > MAX_SIZE:
    raise MeshError(f'{reference}: {size:g} m across; objects are given in metres (a file in '
                    'millimetres takes a scale: path@0.001)')
  centre = 0.5 * (low + high)
  return tuple((h - centre).astype(np.float32) for h in hulls)


@functools.lru_cache(maxsize=256)
def content_hash(reference: str) -> str:
  """SHA-256 over the bytes of every file the object is read from, and its scale: what a policy
  records of the objects it trained on."""
  path, scale = split_reference(reference)
  files = sorted(p for p in path.iterdir() if p.suffix.lower() in SUFFIXES) if path.is_dir() else [
      path]
  digest = hashlib.sha256(f'{scale:g}'.encode())
  for p in files:
    digest.update(p.read_bytes())
  return digest.hexdigest()
