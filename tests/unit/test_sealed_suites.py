"""The sealed test suites are what their manifest records and hold nothing that chose a recipe: no
development or validation layout (`suites/similarity.py`), no occluder pose of theirs, and packed
arrangement types that no training or validation draw holds (`arrangements.HELD_OUT`)."""
import hashlib
import json
import pathlib

import numpy as np
import pytest

from mvcoba_jax.sim import arrangements, occluders
from mvcoba_jax.sim.scenarios import read_case
from mvcoba_jax.suites import DEVELOPMENT, SEALED, SUITES_DIR, generate
from mvcoba_jax.suites.similarity import shares_layout

VALIDATION = pathlib.Path(__file__).resolve().parents[2] / 'docs' / 'results' / 'validation'


def cases_of(folder: pathlib.Path):
  return [read_case(f) for f in sorted(folder.glob('*.scn'))]


@pytest.fixture(scope='module')
def chosen_on():
  """Every case a recipe could have been chosen on: development and validation suites."""
  folders = [SUITES_DIR / s for s in DEVELOPMENT] + sorted(VALIDATION.iterdir())
  return [c for folder in folders for c in cases_of(folder)]


def test_the_sealed_files_are_the_manifests():
  manifest = json.loads((SUITES_DIR / 'manifest.json').read_text())
  assert list(manifest['suites']) == list(SEALED)
  for suite, record in manifest['suites'].items():
    files = sorted((SUITES_DIR / suite).glob('*.scn'))
    assert {f.name: hashlib.sha256(f.read_bytes()).hexdigest() for f in files} == \
        record['sha256'], f'{suite}: its files are not the ones sealed'


def test_sealed_packed_cases_are_the_generators_draws():
  """Each packed case is one of the first 20 draws its manifest names (which one passed the
  load check is physics, tested in tests/sim/test_scenarios.py)."""
  for k, kind in enumerate(arrangements.HELD_OUT):
    for i, f in enumerate(sorted((SUITES_DIR / f'packed-{kind}').glob('*.scn'))):
      draws = [generate.family_case(kind, generate.SEALED_SEED + 3000 + 1000 * k + 100 * t + i)
               for t in range(20)]
      assert f.read_text() in draws, f.name
  for i, f in enumerate(sorted((SUITES_DIR / 'ordered').glob('*.scn'))):
    kind = arrangements.TRAINING[i % len(arrangements.TRAINING)]
    draws = [generate.family_case(kind, generate.SEALED_SEED + 1000 + 100 * t + i)
             for t in range(20)]
    assert f.read_text() in draws, f.name


def test_held_out_types_are_never_drawn_for_training_or_validation():
  assert not set(arrangements.HELD_OUT) & set(arrangements.TRAINING)
  assert set(arrangements.HELD_OUT) | set(arrangements.TRAINING) == set(arrangements.TYPES)
  held_out = [f'packed-{kind}' for kind in arrangements.HELD_OUT]
  assert set(held_out) <= set(SEALED)


@pytest.mark.parametrize('suite', SEALED)
def test_no_sealed_case_is_a_development_or_validation_case_moved(suite, chosen_on):
  """No rigid motion of the table puts half of a sealed case's objects, and four or more, on
  same-shape objects of a case that chose a recipe."""
  for case in cases_of(SUITES_DIR / suite):
    shared = [other.name for other in chosen_on if shares_layout(case, other)]
    assert not shared, (case.name, shared)


def test_no_sealed_occluder_stands_where_a_chosen_on_one_did(chosen_on):
  """Sealed occluders come from the test region, which training keeps its margins from
  (tests/unit/test_occluders.py), and none stands within 1 cm and 5 degrees of a development or
  validation one."""
  poses = lambda cases: np.array([(*o.pos, o.yaw) for c in cases for o in c.occluders])
  sealed, seen = poses(cases_of(SUITES_DIR / 'occluded')), poses(chosen_on)
  assert len(sealed) >= 12
  distance, turn = occluders.separation(sealed, seen)
  near, turned = generate.SAME_POSE
  assert ((distance > near) | (turn > turned)).all(), (distance.min(), turn.min())


def test_the_generator_refuses_a_suite_it_does_not_write(capsys):
  """Before anything is drawn: a name that is not a suite of the kind asked for, in one line."""
  for argv, listed in ((['--only', 'bogus'], 'dev-random'),
                       (['--validation', 'out', '--only', 'random'], 'val-packed')):
    with pytest.raises(SystemExit):
      generate.main(argv)
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert f'--only {argv[-1]}: not among' in err and listed in err
