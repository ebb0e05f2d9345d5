"""Training occluders keep their margin from every occluder of the shipped test suites, and the
validation cases' occluders stand apart from both (sim/occluders.py)."""
import math
import pathlib

import jax
import numpy as np
import pytest

from mvcoba_jax.config import resolve
from mvcoba_jax.sim import occluders
from mvcoba_jax.sim.scenarios import read_case
from mvcoba_jax.sim.tabletop import Tabletop
from mvcoba_jax.suites import SUITES, SUITES_DIR

VALIDATION = pathlib.Path(__file__).resolve().parents[2] / 'docs' / 'results' / 'validation'


def case_poses(files) -> np.ndarray:
  """(n, 4) x, y, z, yaw of every occluder of the case files."""
  poses = [(*o.pos, o.yaw) for f in files for o in read_case(f).occluders]
  return np.array(poses, np.float64).reshape(-1, 4)


@pytest.fixture(scope='module')
def shipped():
  files = [f for suite in SUITES for f in sorted((SUITES_DIR / suite).glob('*.scn'))]
  poses = case_poses(files)
  assert len(poses) >= 20  # the occluded suite's 12 cases hold 20 occluders
  return poses


@pytest.fixture(scope='module')
def training():
  """Occluder poses of 4096 training drops with every drop occluded, as `reset` draws them."""
  env = Tabletop(resolve('tiny', ['env.occluded_share=1']).tabletop)
  keys = jax.random.split(jax.random.PRNGKey(0), 4096)
  pos, quat = jax.jit(jax.vmap(env.drawn_occluders))(keys)
  pos, quat = np.asarray(pos), np.asarray(quat)
  placed = pos[..., 2] < 1.0  # the slot in use; the others are parked high above
  assert (placed.sum(axis=1) == 1).all() and placed[:, 0].any() and placed[:, 1].any()
  yaw = 2 * np.arctan2(quat[..., 3], quat[..., 0])
  return np.concatenate([pos, yaw[..., None]], axis=-1)[placed]


def test_training_occluders_keep_both_margins_from_every_test_occluder(training, shipped):
  distance, turn = occluders.separation(training, shipped)
  assert distance.min() >= occluders.MARGIN_M, distance.min()
  assert turn.min() >= occluders.MARGIN_DEG, turn.min()


def test_training_occluders_vary_in_every_coordinate(training):
  """Both cameras, both sides, a spread of heights and turns: a distribution, not a pose."""
  x, y, z, yaw = training.T
  assert (x > 0).any() and (x < 0).any() and np.ptp(y) > 0.08 and np.ptp(z) > 0.05
  turn = np.abs((np.degrees(yaw) + 90) % 180 - 90)
  assert turn.min() >= 23 - 1e-3 and turn.max() <= 40 + 1e-3 and np.ptp(turn) > 10


@pytest.mark.parametrize('suite', ['val-occluded', 'val-occluded-high'])
def test_validation_occluders_stand_apart_from_training_and_test(suite, training, shipped):
  poses = case_poses(sorted((VALIDATION / suite).glob('*.scn')))
  assert len(poses) >= 6
  distance, turn = occluders.separation(poses, shipped)
  assert distance.min() >= occluders.MARGIN_M, distance.min()
  distance, turn = occluders.separation(poses, training)
  assert distance.min() >= occluders.MARGIN_M and turn.min() >= occluders.MARGIN_DEG


def test_separation_folds_yaws_by_a_half_turn():
  a = np.array([[0.3, 0.0, 0.5, 0.0]])
  b = np.array([[0.3, 0.04, 0.5, math.radians(170.0)], [0.3, 0.0, 0.5, math.radians(-20.0)]])
  distance, turn = occluders.separation(a, b)
  assert distance[0] == pytest.approx([0.04, 0.0]) and turn[0] == pytest.approx([10.0, 20.0])
