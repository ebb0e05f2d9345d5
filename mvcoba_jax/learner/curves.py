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
  """(grasp attempts x, grasp success), (actions x, successful grasps per action) over sliding
  windows. Not the paper's action efficiency (objects per action of completed test runs)."""
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
              ylabel=f'successful grasps per action (last {window})', ylim=(0, 1))
  for a in axes:
    a.grid(alpha=0.3)
  if title:
    fig.suptitle(title)
  fig.tight_layout()
  fig.savefig(path, dpi=100)


def on_actions(primitives, successes, window: int) -> tuple[np.ndarray, np.ndarray]:
  """Both curves of one run at every training action (grasp success held between grasps)."""
  (gx, gy), (_, efficiency) = training_curves(np.asarray(primitives), np.asarray(successes),
                                              window)
  actions = np.arange(1, len(primitives) + 1)
  return np.interp(actions, gx, gy) if len(gx) else np.zeros(len(actions)), efficiency


def plot_groups(groups: dict[str, list[tuple[np.ndarray, np.ndarray]]], window: int,
                folder: str | pathlib.Path) -> list[pathlib.Path]:
  """One PNG per metric (curves-grasp_success.png, curves-grasps_per_action.png): per group
  (a method), the mean over its runs (seeds) with a band from their lowest to their highest."""
  paths = []
  for m, (metric, label) in enumerate((('grasp_success', f'grasp success (last {window} grasps)'),
                                       ('grasps_per_action',
                                        f'successful grasps per action (last {window})'))):
    fig = Figure(figsize=(8, 4.5))
    ax = fig.subplots()
    for name, runs in groups.items():
      length = min(len(run[0]) for run in runs)
      series = np.stack([run[m][:length] for run in runs])
      actions = np.arange(1, length + 1)
      line, = ax.plot(actions, 100 * series.mean(axis=0), label=f'{name} ({len(runs)} seeds)')
      ax.fill_between(actions, 100 * series.min(axis=0), 100 * series.max(axis=0),
                      color=line.get_color(), alpha=0.2)
    ax.set(xlabel='training actions', ylabel=f'{label} (%)', ylim=(0, 100))
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    paths.append(pathlib.Path(folder) / f'curves-{metric}.png')
    fig.savefig(paths[-1], dpi=100)
  return paths
