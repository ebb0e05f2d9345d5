"""The occluded suite's cases with their occluders moved (experiments/occluded_gap.py): each
condition puts them in the region it names, keeps the objects, and its table pools seeds."""
import math
import pathlib
import sys

import numpy as np
import pytest

from mvcoba_jax.config import resolve
from mvcoba_jax.evaluation.report import METRICS
from mvcoba_jax.sim import occluders
from mvcoba_jax.sim.scenarios import read_case
from mvcoba_jax.suites import SUITES_DIR

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / 'experiments'))
import occluded_gap  # noqa: E402

CAMERAS_XY = [c.pos[:2] for c in resolve('default').scene.cameras]


@pytest.fixture(scope='module')
def folders(tmp_path_factory):
  return occluded_gap.write_conditions(tmp_path_factory.mktemp('gap'), CAMERAS_XY)


def poses(folder) -> np.ndarray:
  found = [(*o.pos, o.yaw) for f in sorted(folder.glob('*.scn')) for o in read_case(f).occluders]
  return np.array(found, np.float64).reshape(-1, 4)


def turns(found) -> np.ndarray:
  return np.array([abs(occluded_gap.facing_turn(x, y, math.degrees(yaw), CAMERAS_XY))
                   for x, y, _, yaw in found])


def test_each_condition_puts_the_occluders_in_its_region(folders):
  test = poses(folders['test'])
  assert len(test) == 20 and (turns(test) <= occluders.TEST.yaw[1] + 1e-6).all()
  for name, region in (('training', occluders.TRAINING), ('validation', occluders.VALIDATION)):
    found = poses(folders[name])
    np.testing.assert_allclose(found[:, :2], test[:, :2])  # along and side kept
    low, high = region.height
    assert (found[:, 2] >= low - 1e-6).all() and (found[:, 2] <= high + 1e-6).all(), name
    low, high = region.yaw
    assert (turns(found) >= low - 1e-3).all() and (turns(found) <= high + 1e-3).all(), name
  distance, turn = occluders.separation(poses(folders['training']), test)
  assert distance.min() >= occluders.MARGIN_M and turn.min() >= occluders.MARGIN_DEG
  assert len(poses(folders['none'])) == 0


def test_only_the_named_conditions_are_written(tmp_path):
  folders = occluded_gap.write_conditions(tmp_path, CAMERAS_XY, ('test', 'none'))
  assert list(folders) == ['test', 'none'] and not (tmp_path / 'cases' / 'training').exists()


def test_the_objects_stay_where_the_shipped_cases_put_them(folders):
  for shipped in sorted((SUITES_DIR / 'dev-occluded').glob('*.scn')):
    objects = read_case(shipped).objects
    for folder in folders.values():
      assert read_case(folder / shipped.name).objects == objects


def test_facing_turn_folds_a_half_turn_and_reads_from_the_nearer_camera():
  assert occluded_gap.facing_turn(0.3, 0.0, -3.1, CAMERAS_XY) == pytest.approx(-3.1)
  assert occluded_gap.facing_turn(-0.27, 0.04, 178.4, CAMERAS_XY) == pytest.approx(-1.6)
  assert occluded_gap.facing_turn(-0.27, 0.04, 7.8, CAMERAS_XY) == pytest.approx(7.8)


def test_the_table_pools_seeds_pairs_them_with_none_and_keeps_the_cases_seen_by_some_camera():
  """Two seeds; case b hides an object from both cameras under the test's occluders, so the
  second block leaves it out. With occluders: seed means (70, 50) over both cases, (80, 60) over
  a alone; with none, 10 points more on every case of seed 0 and 20 on seed 1."""
  def row(seed, more):
    score = {'a': 80.0 - 20 * seed, 'b': 60.0 - 20 * seed}
    return {'settings': {'training_seed': seed}, 'cases': {
        c: {key: score[c] + more[seed] for key, _ in METRICS} for c in score}}
  folders = {name: pathlib.Path(name) for name in ('test', 'none')}
  results = {'test': {f'mvcoba (mvcoba-s{s})': row(s, (0, 0)) for s in (0, 1)},
             'none': {f'mvcoba (mvcoba-s{s})': row(s, (10, 20)) for s in (0, 1)}}
  sight = lambda hidden: {'per_case': {'a': {'one_camera_only': 1, 'no_camera': 0},
                                       'b': {'one_camera_only': 0, 'no_camera': hidden}}}
  text = occluded_gap.table(results, folders, {'test': sight(2), 'none': sight(0)})
  every, some = text.split('seen by some camera (a):')
  assert '| test (mvcoba) | 1 / 2 | 2 | 60.0 [' in every and '70.0 / 50.0 |' in every
  assert '| -15.0 [' in every  # paired: seed differences -10 and -20
  assert '| none (mvcoba) | 1 / 0 | 2 | 75.0 [' in every and '| 0.0 [0.0, 0.0] |' in every
  assert '| test (mvcoba) | 1 / 0 | 2 | 70.0 [' in some and '80.0 / 60.0 |' in some
  assert '| test | 70.0 | 50.0 |' in text and '| none | 85.0 | 65.0 |' in text
