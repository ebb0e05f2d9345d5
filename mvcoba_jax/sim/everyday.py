"""Held-out everyday objects: a dozen household items modelled as convex parts from the YCB object
set's published sizes (Calli et al., 2015; rounded to the millimetre, approximate), for the
`novel` suite. No training pool holds them, and no procedural kind is like them: hollow vessels
(mug, cup, bowl), cans and bottles, curved fruit, balls, thin markers and flat boxes.

These are models of the objects' shapes, not scans: Google Scanned Objects' meshes (the issue's
first choice) could not be brought onto the machines this set was built on, and any folder of
parts (`model_collision_*.obj`) evaluates the same way (docs/objects.md).

    python -m mvcoba_jax.sim.everyday OUT
"""
from __future__ import annotations

import argparse
import json
import pathlib

import numpy as np

from mvcoba_jax.sim import procedural

SIDES = 16  # sides of a round part's polygon


def _cylinder(radius, height, z=0.0, sides=SIDES, axis=2) -> np.ndarray:
  ang = 2 * np.pi * (np.arange(sides) + 0.5) / sides
  ring = np.stack([radius * np.cos(ang), radius * np.sin(ang)], axis=1)
  points = np.concatenate([np.insert(ring, 2, z + s * height / 2, axis=1) for s in (-1, 1)])
  return points[:, [2, 0, 1]] if axis == 0 else points


def _walls(outer, height, wall, bottom, top_outer=None, segments=8) -> list[np.ndarray]:
  """A vessel: a base disc and `segments` wall pieces, flaring to `top_outer` at the rim."""
  top_outer = top_outer or outer
  parts = [_cylinder(outer - wall, bottom, z=bottom / 2)]
  for i in range(segments):
    a0, a1 = 2 * np.pi * i / segments, 2 * np.pi * (i + 1) / segments
    piece = []
    for z, r in ((0.0, outer), (height, top_outer)):
      for a in (a0, a1):
        for rr in (r, r - wall):
          piece.append((rr * np.cos(a), rr * np.sin(a), z))
    parts.append(np.array(piece))
  return parts


def _ellipsoid(radii, n=64) -> np.ndarray:
  golden = np.pi * (3.0 - np.sqrt(5.0))  # a Fibonacci sphere: even, no random stream
  z = 1 - 2 * (np.arange(n) + 0.5) / n
  r = np.sqrt(1 - z * z)
  points = np.stack([r * np.cos(golden * np.arange(n)), r * np.sin(golden * np.arange(n)), z], 1)
  return points * np.asarray(radii)


def _banana() -> list[np.ndarray]:
  """Four segments along an arc of 19.7 cm chord, 3.6 cm thick, lying on the table."""
  radius, sweep = 0.114, np.deg2rad(90)
  parts = []
  for i in range(4):
    a = -sweep / 2 + sweep * np.array([i, i + 1]) / 4
    centres = np.stack([radius * np.sin(a), radius * (1 - np.cos(a)), [0.0, 0.0]], axis=1)
    parts.append(np.concatenate([c + _ellipsoid((0.018, 0.018, 0.016), 24) for c in centres]))
  return parts


def objects() -> dict[str, list[np.ndarray]]:
  """Name -> convex parts (metres, resting as they lie on a table)."""
  mug = _walls(0.043, 0.081, 0.005, 0.006)
  mug += [procedural.box((0.058, 0.0, 0.066), (0.03, 0.012, 0.012)),
          procedural.box((0.068, 0.0, 0.04), (0.012, 0.012, 0.05)),
          procedural.box((0.058, 0.0, 0.016), (0.03, 0.012, 0.012))]
  return {
      'mug': mug,
      'cup': _walls(0.034, 0.065, 0.004, 0.005, top_outer=0.04),
      'bowl': _walls(0.05, 0.053, 0.006, 0.006, top_outer=0.08),
      'soup_can': [_cylinder(0.033, 0.101)],
      'tuna_can': [_cylinder(0.043, 0.033)],
      # lying on its side, cap along +x
      'mustard_bottle': [procedural.box((0, 0, 0), (0.15, 0.058, 0.058)),
                         _cylinder(0.012, 0.04, axis=0) + (0.095, 0.0, 0.0)],
      'banana': _banana(),
      'apple': [_ellipsoid((0.0375, 0.0375, 0.035))],
      'tennis_ball': [_ellipsoid((0.032, 0.032, 0.032))],
      'large_marker': [_cylinder(0.009, 0.121, axis=0)],
      'pudding_box': [procedural.box((0, 0, 0), (0.11, 0.089, 0.035))],
      'gelatin_box': [procedural.box((0, 0, 0), (0.089, 0.073, 0.028))],
  }


def write_set(folder) -> list[str]:
  """Writes every object as `folder/NAME/model_collision_*.obj` and a manifest.json."""
  folder = pathlib.Path(folder)
  for name, parts in objects().items():
    procedural.write_object(folder / name, parts)
  manifest = {'generator': 'python -m mvcoba_jax.sim.everyday',
              'source': 'shapes modelled from the YCB object set\'s published sizes '
                        '(Calli et al., 2015), not scans', 'objects': list(objects())}
  (folder / 'manifest.json').write_text(json.dumps(manifest, indent=1) + '\n')
  return list(objects())


def main(argv=None) -> None:
  parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
  parser.add_argument('out', help='folder to write the objects into')
  print('\n'.join(write_set(parser.parse_args(argv).out)))


if __name__ == '__main__':
  main()
