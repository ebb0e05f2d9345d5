"""Whether one case's layout is another's moved: the most objects of case A that one rigid
motion of the table plane (a turn, a mirror image, and a shift) puts within `TOLERANCE` of an
object of the same shape in case B. Validation cases are drawn so that no shipped case shares
more than a few of their objects (`shares_layout`, tests/unit/test_validation_cases.py); a case
turned and shifted would share all of them."""
from __future__ import annotations

import itertools
import math

import numpy as np

TOLERANCE = 0.01  # m between an object's centre moved and the centre it lands on


def _plane(case) -> tuple[np.ndarray, list[str]]:
  return np.array([o.pos[:2] for o in case.objects], np.float64), [o.shape for o in case.objects]


def largest_rigid_match(a, b, tolerance: float = TOLERANCE, at_least: int = 2) -> int:
  """The most objects of case `a` that one rigid motion of the plane puts, each within
  `tolerance`, on a distinct object of the same shape in case `b` (yaws not compared). Every
  motion that maps a pair of `a`'s objects onto a pair of `b`'s of the same shapes and distance
  is tried, mirrored and not. With `at_least`, only the pairs among `a`'s first n - at_least + 2
  objects: any `at_least` of its n objects hold two of those, so a match that large is still
  found (and the count is exact from there), in a fraction of the time for large cases."""
  pa, sa = _plane(a)
  anchors = range(min(len(pa), max(2, len(pa) - at_least + 2)))
  pb, sb = _plane(b)
  kinds = {shape: n for n, shape in enumerate(dict.fromkeys(sa + sb))}
  ka, kb = np.array([kinds[s] for s in sa]), np.array([kinds[s] for s in sb])
  best = int(bool(set(sa) & set(sb)))
  k, m = (x.ravel() for x in np.meshgrid(np.arange(len(pb)), np.arange(len(pb)), indexing='ij'))
  k, m = k[k != m], m[k != m]
  db = pb[m] - pb[k]
  lengths_b, angles_b = np.hypot(db[:, 0], db[:, 1]), np.arctan2(db[:, 1], db[:, 0])
  same = ka[:, None] == kb[None]
  for mirror in (1.0, -1.0):
    src = pa * [1.0, mirror]
    for i, j in itertools.permutations(anchors, 2):
      d = src[j] - src[i]
      fits = np.flatnonzero((kb[k] == ka[i]) & (kb[m] == ka[j])
                            & (np.abs(lengths_b - np.hypot(*d)) <= 2 * tolerance))
      if not fits.size:
        continue
      angle = angles_b[fits] - np.arctan2(d[1], d[0])
      c, s = np.cos(angle)[:, None, None], np.sin(angle)[:, None, None]
      local = (src - src[i])[None]
      moved = np.stack([local[..., 0] * c[..., 0] - local[..., 1] * s[..., 0],
                        local[..., 0] * s[..., 0] + local[..., 1] * c[..., 0]], -1) \
          + pb[k[fits]][:, None]
      near = (np.linalg.norm(moved[:, :, None] - pb[None, None], axis=-1) <= tolerance) & same
      # Objects near some same-shape object bound the match from above: only motions whose
      # bound beats the best so far are matched one to one.
      for f in np.flatnonzero(near.any(axis=2).sum(axis=1) > best):
        best = max(best, _matched(near[f]))
  return best


def shares_layout(a, b, of: int | None = None) -> bool:
  """Whether one rigid motion of the table puts half of `of` objects (`a`'s count if None), and
  four or more, of case `a` on same-shape objects of case `b`: `a` is `b` moved, or much of it."""
  need = math.ceil(max(4, (len(a.objects) if of is None else of) / 2))
  return largest_rigid_match(a, b, at_least=need) >= need


def _matched(near) -> int:
  """Objects of the moved case matched, greedily, each to a distinct object it is `near`."""
  taken, count = np.zeros(near.shape[1], bool), 0
  for row in near:
    free = np.flatnonzero(row & ~taken)
    if free.size:
      taken[free[0]] = True
      count += 1
  return count
