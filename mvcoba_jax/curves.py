"""Training curves of the paper (Figures 9 and 10) from the per-action log."""
from __future__ import annotations

import pathlib

import numpy as np
from matplotlib.figure import Figure  # no pyplot: no global backend, no display needed


def windowed_rate(hits: np.ndarray, window: int) -> np.ndarray:
  """Rate over the last `window` entries; the first ones are divided by `window` too.

  That is the paper's i/window scaling: early points are not inflated by small counts.
  """
  cumulative = np.concatenate([[0], np.cumsum(hits, dtype=np.float64)])
  index = np.arange(1, len(hits) + 1)
  return (cumulative[index] - cumulative[np.maximum(index - window, 0)]) / window


def training_curves(primitives: np.ndarray, successes: np.ndarray, window: int):
  """(grasp attempts x, grasp success), (actions x, action efficiency) over sliding windows."""
  grasps = primitives == 1
  success = windowed_rate(successes[grasps].astype(float), window)
  efficiency = windowed_rate(successes.astype(float), window)
  return (np.flatnonzero(grasps) + 1, success), (np.arange(1, len(primitives) + 1), efficiency)


def plot(primitives, successes, window: int, path: str | pathlib.Path, title: str = '') -> None:
  (gx, gy), (ax_, ay) = training_curves(np.asarray(primitives), np.asarray(successes), window)
  fig = Figure(figsize=(10, 3.5))
  axes = fig.subplots(1, 2)
  axes[0].plot(gx, gy)
  axes[0].set(xlabel='training actions', ylabel=f'grasp success (last {window} grasps)',
              ylim=(0, 1))
  axes[1].plot(ax_, ay, color='tab:orange')
  axes[1].set(xlabel='training actions',
              ylabel=f'action efficiency (last {window} actions)', ylim=(0, 1))
  for a in axes:
    a.grid(alpha=0.3)
  if title:
    fig.suptitle(title)
  fig.tight_layout()
  fig.savefig(path, dpi=100)
