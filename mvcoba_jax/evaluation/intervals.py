"""Interval estimates of a method's score over training seeds: the stratified bootstrap of Agarwal
et al. (2021, "Deep RL at the Edge of the Statistical Precipice"), seeds resampled with
replacement within each case, through `scipy.stats.bootstrap` (one sample per case)."""
from __future__ import annotations

import math

import numpy as np
from scipy import stats

STATISTICS = ('mean', 'iqm')  # iqm: the interquartile mean, robust to an outlying seed


def _statistic(name: str):
  def mean_of_cases(*cases, axis=-1):
    pooled = np.concatenate(cases, axis=axis)
    return np.mean(pooled, axis=axis) if name == 'mean' else stats.trim_mean(pooled, 0.25,
                                                                             axis=axis)
  return mean_of_cases


def interval(scores, statistic: str = 'mean', confidence: float = 0.95, resamples: int = 5000,
             seed: int = 0) -> tuple[float, float, float]:
  """(point, low, high) of `statistic` over `scores` (seeds, cases), NaN-free. With one seed there
  is nothing to resample: the interval is (nan, nan) around the point."""
  scores = np.asarray(scores, np.float64)
  if scores.ndim != 2 or not scores.size or not np.isfinite(scores).all():
    raise ValueError(f'scores must be a finite (seeds, cases) array, got shape {scores.shape}')
  if statistic not in STATISTICS:
    raise ValueError(f'statistic {statistic!r}: one of {", ".join(STATISTICS)}')
  fn = _statistic(statistic)
  point = float(fn(*scores.T))
  if scores.shape[0] < 2:
    return point, math.nan, math.nan
  if np.ptp(scores, axis=0).max() == 0:  # every seed agrees in every case
    return point, point, point
  result = stats.bootstrap(tuple(scores.T), fn, n_resamples=resamples,
                           confidence_level=confidence, method='percentile', vectorized=True,
                           paired=False, rng=np.random.default_rng(seed))
  low, high = result.confidence_interval
  return point, float(low), float(high)


def separated(a: tuple[float, float, float], b: tuple[float, float, float]) -> bool:
  """Whether two intervals are disjoint: the only case in which we call one method better."""
  return all(math.isfinite(v) for v in a[1:] + b[1:]) and (a[2] < b[1] or b[2] < a[1])
