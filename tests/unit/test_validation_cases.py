"""The validation suites (docs/results/validation) are what the generator writes and share no
layout with any test case: no rigid motion of the table puts half of a validation case's
objects, and four or more, on same-shape objects of a sealed, isolated or VPG case
(suites/similarity.py). Three
objects of a few set apart can land on a heap of 36 by chance; a case moved lands whole."""
import pathlib

import pytest

from mvcoba_jax.sim import arrangements, occluders
from mvcoba_jax.sim.scenarios import read_case
from mvcoba_jax.suites import SEALED, SUITES_DIR, generate, novel
from mvcoba_jax.suites.similarity import largest_rigid_match, shares_layout

VALIDATION = pathlib.Path(__file__).resolve().parents[2] / 'docs' / 'results' / 'validation'
KINDS = generate.VALIDATION_SUITES


def files(folder: pathlib.Path):
  return sorted(p for p in folder.glob('*.*') if p.suffix in ('.scn', '.txt'))


@pytest.fixture(scope='module')
def shipped():
  """The test suites: sealed, isolated and VPG's (validation and development suites both serve
  choosing, so they may share a template)."""
  return [read_case(f) for suite in (*SEALED, 'isolated', 'vpg')
          for f in files(SUITES_DIR / suite)]


def test_validation_files_are_the_generators():
  assert sorted(p.name for p in VALIDATION.iterdir()) == sorted(KINDS + (novel.TWIN,))
  ordered = [f.read_text() for f in files(VALIDATION / 'val-ordered')]
  assert ordered == [generate.packed_case(i) for i in range(6)]
  for i, f in enumerate(files(VALIDATION / 'val-packed')):
    kind = arrangements.TRAINING[i % len(arrangements.TRAINING)]
    draws = [generate.family_case(kind, generate.VALIDATION_SEED + 900 + 100 * t + i)
             for t in range(20)]
    assert f.read_text() in draws, f.name
  for i, f in enumerate(files(VALIDATION / 'val-occluded')):
    draws = [generate.drawn_occluded_case(occluders.VALIDATION,
                                          generate.VALIDATION_SEED + 500 + 100 * t + i, i)
             for t in range(20)]
    assert f.read_text() in draws, f.name
  for i, f in enumerate(files(VALIDATION / 'val-occluded-high')):
    draws = [generate.drawn_occluded_case(occluders.VALIDATION_HIGH,
                                          generate.VALIDATION_HIGH_SEED + 100 * t + i, i,
                                          generate.HIGH_KINDS) for t in range(20)]
    assert f.read_text() in draws, f.name


@pytest.mark.parametrize('kind', KINDS)
def test_no_validation_case_is_a_shipped_case_moved(kind, shipped):
  for f in files(VALIDATION / kind):
    case = read_case(f)
    shared = [other.name for other in shipped if shares_layout(case, other)]
    assert not shared, (f.name, shared)


def test_the_match_finds_a_case_turned_mirrored_and_shifted(tmp_path):
  """dev-ordered's framed square (without its isolated object) turned 32.7 degrees, mirrored
  and moved matches all 12 of its objects; a brick bond of the same blocks shares few."""
  source = read_case(SUITES_DIR / 'dev-ordered' / 'dev-ordered-03.scn')
  parts = [(o.shape, o.pos[0], -o.pos[1], 0.0) for o in source.objects[:-1]]
  moved = tmp_path / 'moved.scn'
  moved.write_text(generate.HEADER + ''.join(generate.turned(parts, 32.7, 0.01, -0.02)))
  assert largest_rigid_match(read_case(moved), source) == len(parts) == 12
  brick = read_case(VALIDATION / 'val-ordered' / 'val-ordered-00.scn')
  assert largest_rigid_match(brick, source) <= 3
