"""Interval estimates of a method's score with the training seed as the unit.

One network per seed plays every case, so a seed's luck is shared by all its cases: the cases of
one seed are not independent draws, the seeds are. Each seed's mean over the cases is one
observation, and the interval is Student's t over those per-seed means. In a simulation with a
seed effect shared across cases (experiments/interval_coverage.py, docs/results/intervals.md) it
covers the truth about as often as it says at 5 seeds, where resampling seeds within each case
(the stratified bootstrap) covers it in well under half of the experiments and a percentile
bootstrap over whole seeds in about 84%.

A claim that one method beats another needs `CLAIM_SEEDS` seeds on both sides and disjoint
intervals; with fewer, tables give the per-seed means and make no claim.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import stats

CLAIM_SEEDS = 5  # the fewest training seeds behind each of two intervals for a claim between them


def seed_means(scores) -> np.ndarray:
  """(seeds,) each seed's mean over its cases, from finite `scores` (seeds, cases)."""
  scores = np.asarray(scores, np.float64)
  if scores.ndim != 2 or not scores.size or not np.isfinite(scores).all():
    raise ValueError(f'scores must be a finite (seeds, cases) array, got shape {scores.shape}')
  return scores.mean(axis=1)


def interval(scores, confidence: float = 0.95,
             within: tuple[float, float] = (-math.inf, math.inf)) -> tuple[float, float, float]:
  """(mean, low, high): the mean over seeds and cases of `scores` (seeds, cases) and Student's t
  interval over the per-seed means, cut to the range `within` the score can take (a rate's
  [0, 100]). With one seed there is no spread to measure: (nan, nan)."""
  means = seed_means(scores)
  point = float(means.mean())
  n = means.size
  if n < 2:
    return point, math.nan, math.nan
  half = stats.t.ppf(0.5 + confidence / 2, n - 1) * means.std(ddof=1) / math.sqrt(n)
  return point, float(max(point - half, within[0])), float(min(point + half, within[1]))


def paired(scores, baseline, confidence: float = 0.95) -> tuple[float, float, float] | None:
  """`interval` of `scores` less `baseline`, both (seeds, cases) from the same seeds' networks
  (one network under two conditions): each seed's own difference is the observation, so the
  seed's luck, shared by both, cancels. None where either is undefined in some cell (NaN, or None
  as results.json stores it)."""
  difference = np.array(scores, np.float64) - np.array(baseline, np.float64)
  return interval(difference, confidence) if np.isfinite(difference).all() else None


def separated(a: tuple[float, float, float], b: tuple[float, float, float],
              seeds: tuple[int, int]) -> bool:
  """Whether `a` and `b` (intervals over `seeds` training seeds each) are disjoint with
  `CLAIM_SEEDS` or more seeds behind each: the only case in which we call one method better."""
  return (min(seeds) >= CLAIM_SEEDS and all(math.isfinite(v) for v in a[1:] + b[1:])
          and (a[2] < b[1] or b[2] < a[1]))
