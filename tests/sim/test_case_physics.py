"""Test cases settle where they are listed: the public VPG cases and one written here."""
import jax
import numpy as np
import pytest

from mvcoba_jax.sim.scenarios import case_to_layout, read_case, stack_layouts
from mvcoba_jax.suites import SUITES_DIR
from tests.helpers import BACKENDS, make_env
from tests.penetration import max_penetration

# A VPG-format case of our own: a cube, a lying tall box, a disk and a parked line.
OWN_CASE = """\
4.obj 0.3 0.5 0.7 -0.55 0.05 0.026 0 0 0.4
6.obj 0.9 0.5 0.2 -0.40 -0.10 0.026 1.5708 0 0
7.obj 0.2 0.8 0.3 -0.62 -0.12 0.013 0 0 0
3.obj 0.5 0.5 0.5 -0.89 -0.39 0.026 0 0 0
"""


@pytest.fixture(scope='module', params=BACKENDS)
def settled(request, tmp_path_factory):
  env = make_env('default', request.param)
  own = tmp_path_factory.mktemp('cases') / 'own-case.txt'
  own.write_text(OWN_CASE)
  paths = [own] + sorted((SUITES_DIR / 'vpg').glob('test-10-obj-*.txt'))
  cases = [read_case(p) for p in paths]
  states = jax.jit(jax.vmap(env.reset_from_case))(
      stack_layouts([case_to_layout(c, env) for c in cases]))
  return env, cases, states


def test_own_case_and_all_eleven_public_cases_are_loaded(settled):
  env, cases, states = settled
  assert len(cases[0].objects) == 3
  assert len(cases) == 12


@pytest.mark.parametrize('case_index', range(12))
def test_case_settles_in_place_without_interpenetration(settled, case_index):
  env, cases, states = settled
  case = cases[case_index]
  layout = case_to_layout(case, env)
  pos = np.asarray(env.object_positions(jax.tree.map(lambda x: x[case_index], states)))
  used = np.flatnonzero(np.asarray(layout.in_play))
  assert np.asarray(states.in_play[case_index])[used].all(), f'{case.name}: an object was lost'
  listed = np.asarray(layout.pos)[used, :2]
  drift = np.linalg.norm(pos[used, :2] - listed, axis=1)
  assert drift.max() < 0.01, f'{case.name}: drift per object {np.round(drift, 4)}'
  assert max_penetration(env, states.sim.qpos[case_index]) < 0.002
  assert bool(states.healthy[case_index])
