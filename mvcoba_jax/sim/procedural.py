"""Procedural training objects beyond the blocks: a seeded generator of grasp-sized shapes, each a
set of convex parts written as a folder of `model_collision_*.obj` files (the layout `meshes`
reads for an object already split).

Kinds: random convex polyhedra, rounded and elongated solids (hulls of points on an ellipsoid),
bars, and concave composites of boxes: L, T and U shapes and square rings. Every object's
narrowest horizontal side fits between the open fingers with room to spare, and its largest side
is 3-12 cm, as the blocks' are.

    python -m mvcoba_jax.sim.procedural OUT --count 24 --seed 0
"""
from __future__ import annotations

import argparse
import json
import pathlib

import numpy as np

KINDS = ('convex', 'rounded', 'bar', 'ell', 'tee', 'u', 'ring')
OBJECTS = pathlib.Path(__file__).resolve().parent / 'objects'
# The shipped sets: training's (seed 0) and validation's (seed 1), 14 objects each.
SETS = {'procedural': 0, 'procedural-val': 1}
SET_SIZE = 14


def training_objects() -> list[pathlib.Path]:
  """The object folders of the shipped training set, in order."""
  return sorted(p for p in (OBJECTS / 'procedural').iterdir() if p.is_dir())


def box(centre, size) -> np.ndarray:
  """The 8 corners of a box of `size` about `centre`."""
  corners = np.array([[x, y, z] for x in (-.5, .5) for y in (-.5, .5) for z in (-.5, .5)])
  return np.asarray(centre) + corners * np.asarray(size)


def _ellipsoid_points(rng, radii, n) -> np.ndarray:
  directions = rng.normal(size=(n, 3))
  directions /= np.linalg.norm(directions, axis=1, keepdims=True)
  return directions * np.asarray(radii)


def _resting(vertices: np.ndarray) -> np.ndarray:
  """The points turned so that the hull's face nearest their centroid, the face it comes to
  rest on, lies down (a random hull written as drawn would topple as it settles)."""
  from scipy import spatial  # pylint: disable=import-outside-toplevel
  hull = spatial.ConvexHull(vertices)
  centre = vertices[hull.vertices].mean(axis=0)
  normals, offsets = hull.equations[:, :3], hull.equations[:, 3]
  down = normals[np.argmin(-(normals @ centre + offsets))]
  axis = np.cross(down, [0.0, 0.0, -1.0])
  sin, cos = np.linalg.norm(axis), float(np.dot(down, [0.0, 0.0, -1.0]))
  if sin < 1e-9:
    return vertices if cos > 0 else vertices * [1.0, -1.0, -1.0]
  k = axis / sin
  cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
  turn = np.eye(3) + sin * cross + (1 - cos) * cross @ cross  # Rodrigues
  return vertices @ turn.T


def shape_parts(kind: str, rng: np.random.Generator) -> list[np.ndarray]:
  """The convex parts (vertex arrays, metres) of one object of `kind`, drawn from `rng`."""
  if kind == 'convex':  # a random polyhedron: the hull of a dozen points in a box
    size = rng.uniform([0.03, 0.03, 0.025], [0.07, 0.06, 0.05])
    return [_resting(rng.uniform(-0.5, 0.5, size=(12, 3)) * size)]
  if kind == 'rounded':  # an egg, a pebble or a sausage: points on an ellipsoid, flat side down
    radii = np.sort(rng.uniform([0.015, 0.015, 0.012], [0.05, 0.03, 0.025]))[::-1]
    return [_ellipsoid_points(rng, radii, 48)]
  t = rng.uniform(0.018, 0.03)  # wall thickness of the bars and composites
  h = rng.uniform(0.02, 0.05)  # height
  if kind == 'bar':
    return [box((0, 0, 0), (rng.uniform(0.06, 0.12), t, h))]
  a, b = rng.uniform(0.05, 0.1), rng.uniform(0.05, 0.1)  # arm lengths
  if kind == 'ell':
    return [box((a / 2, t / 2, 0), (a, t, h)), box((t / 2, t + (b - t) / 2, 0), (t, b - t, h))]
  if kind == 'tee':
    return [box((0, 0, 0), (a, t, h)), box((0, -t / 2 - (b - t) / 2, 0), (t, b - t, h))]
  if kind == 'u':
    base = box((0, 0, 0), (a, t, h))
    arms = [box((s * (a - t) / 2, t / 2 + (b - t) / 2, 0), (t, b - t, h)) for s in (-1, 1)]
    return [base] + arms
  if kind == 'ring':  # a square frame: four walls
    side = max(a, 3 * t + 0.02)
    inner = (side - t) / 2
    return [box((0, s * inner, 0), (side, t, h)) for s in (-1, 1)] + [
        box((s * inner, 0, 0), (t, side - 2 * t, h)) for s in (-1, 1)]
  raise ValueError(f'unknown kind {kind!r}; known: {", ".join(KINDS)}')


def _obj_text(vertices: np.ndarray) -> str:
  """An .obj of a convex part: its hull's triangles (`meshes` reads the vertices' hull)."""
  from scipy import spatial  # pylint: disable=import-outside-toplevel
  hull = spatial.ConvexHull(vertices)
  lines = [f'v {x:.6f} {y:.6f} {z:.6f}' for x, y, z in vertices[hull.vertices]]
  index = {v: i + 1 for i, v in enumerate(hull.vertices)}
  lines += [f'f {index[a]} {index[b]} {index[c]}' for a, b, c in hull.simplices]
  return '\n'.join(lines) + '\n'


def write_object(folder: pathlib.Path, parts) -> None:
  """One object as a folder of convex parts, `model_collision_{j}.obj`."""
  folder.mkdir(parents=True, exist_ok=True)
  for j, part in enumerate(parts):
    (folder / f'model_collision_{j}.obj').write_text(_obj_text(part))


def write_set(folder, count: int, seed: int) -> list[str]:
  """Writes `count` objects (kinds in turn, each drawn from `seed`) as `folder/NN_kind/`, and a
  manifest.json of what wrote them; returns the object folders' names."""
  folder = pathlib.Path(folder)
  names = []
  for i in range(count):
    kind = KINDS[i % len(KINDS)]
    rng = np.random.default_rng([seed, i])
    name = f'{i:02d}_{kind}'
    write_object(folder / name, shape_parts(kind, rng))
    names.append(name)
  manifest = {'generator': 'python -m mvcoba_jax.sim.procedural', 'count': count, 'seed': seed,
              'objects': names}
  (folder / 'manifest.json').write_text(json.dumps(manifest, indent=1) + '\n')
  return names


def main(argv=None) -> None:
  parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
  parser.add_argument('out', help='folder to write the objects into')
  parser.add_argument('--count', type=int, default=24)
  parser.add_argument('--seed', type=int, default=0)
  args = parser.parse_args(argv)
  print('\n'.join(write_set(args.out, args.count, args.seed)))


if __name__ == '__main__':
  main()
