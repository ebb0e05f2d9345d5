"""Whether one case's layout is another's moved: the most objects of case A that one rigid
motion of the table plane (a turn, a mirror image, and a shift) puts within `TOLERANCE` of an
object of the same shape in case B. Validation cases are drawn so that no shipped case shares
more than a few of their objects (tests/unit/test_validation_cases.py); a case turned and shifted
would share all of them."""
from __future__ import annotations

import itertools

import numpy as np

TOLERANCE = 0.01  # m between an object's centre moved and the centre it lands on


def _plane(case) -> tuple[np.ndarray, list[str]]:
  return np.array([o.pos[:2] for o in case.objects], np.float64), [o.shape for o in case.objects]


def largest_rigid_match(a, b, tolerance: float = TOLERANCE) -> int:
  """The most objects of case `a` that one rigid motion of the plane puts, each within
  `tolerance`, on a distinct object of the same shape in case `b` (yaws not compared). Every
  motion that maps a pair of `a`'s objects onto a pair of `b`'s of the same shapes and distance
  is tried, mirrored and not."""
  pa, sa = _plane(a)
  pb, sb = _plane(b)
  kinds = {shape: n for n, shape in enumerate(dict.fromkeys(sa + sb))}
  ka, kb = np.array([kinds[s] for s in sa]), np.array([kinds[s] for s in sb])
  best = int(bool(set(sa) & set(sb)))
  k, m = (x.ravel() for x in np.meshgrid(np.arange(len(pb)), np.arange(len(pb)), indexing='ij'))
  k, m = k[k != m], m[k != m]
  db = pb[m] - pb[k]
  lengths_b, angles_b = np.hypot(db[:, 0], db[:, 1]), np.arctan2(db[:, 1], db[:, 0])
  for mirror in (1.0, -1.0):
    src = pa * [1.0, mirror]
    for i, j in itertools.permutations(range(len(pa)), 2):
      d = src[j] - src[i]
      fits = ((kb[k] == ka[i]) & (kb[m] == ka[j])
              & (np.abs(lengths_b - np.hypot(*d)) <= 2 * tolerance))
      for n in np.flatnonzero(fits):
        angle = angles_b[n] - np.arctan2(d[1], d[0])
        c, s = np.cos(angle), np.sin(angle)
        moved = (src - src[i]) @ np.array([[c, s], [-s, c]]) + pb[k[n]]
        best = max(best, _matched(moved, ka, pb, kb, tolerance))
  return best


def _matched(moved, ka, pb, kb, tolerance: float) -> int:
  """Objects of `moved` within `tolerance` of a distinct same-shape object of `pb` (greedy)."""
  near = ((np.hypot(*(moved[:, None] - pb[None]).transpose(2, 0, 1)) <= tolerance)
          & (ka[:, None] == kb[None]))
  taken, count = np.zeros(len(pb), bool), 0
  for row in near:
    free = np.flatnonzero(row & ~taken)
    if free.size:
      taken[free[0]] = True
      count += 1
  return count
