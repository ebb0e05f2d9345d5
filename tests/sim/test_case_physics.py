"""Test cases behave as written: the public VPG cases and one written here settle where they are
listed; a packed ordered case leaves the fingers no room."""
import jax
import numpy as np
import pytest

from mvcoba_jax.config import resolve
from mvcoba_jax.sim import shapes
from mvcoba_jax.sim.primitives import GRASP
from mvcoba_jax.sim.scenarios import case_slots, case_to_layout, read_case, stack_layouts
from mvcoba_jax.sim.tabletop import Tabletop
from mvcoba_jax.suites import SUITES_DIR
from mvcoba_jax.suites import cases as suite_cases
from tests.helpers import BACKENDS, actions, make_env
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


def test_pinwheel_forces_a_push():
  """dev-ordered-00: four flat boxes turned about a disk. A grasp at any block's centre, at any of
  the half turn's 8 rotations, lifts nothing: the fingers land on a neighbour and stop there
  (scene.press_force). The case's isolated cylinder, the control, is lifted."""
  case = read_case(SUITES_DIR / 'dev-ordered' / 'dev-ordered-00.scn')
  config = suite_cases.suite_config(resolve('default'), suite_cases.pool_for([case]))
  env = Tabletop(config.tabletop)
  rotations = env.config.env.num_rotations // 2
  start = jax.jit(env.reset_from_case)(case_to_layout(case, env))
  n = len(case.objects)
  batch = jax.tree.map(lambda a: np.broadcast_to(a, (n * rotations, *a.shape)), start)
  rows = [(GRASP, k, *o.pos[:2], float(shapes.shape(o.shape).rest_extent[2]))
          for o in case.objects for k in range(rotations)]
  end, info = jax.jit(jax.vmap(env.step))(batch, actions(rows))
  slots = np.repeat(case_slots(case, env), rotations)
  lifted = (~np.asarray(end.in_play)[np.arange(n * rotations), slots]
            & (np.asarray(info.picked) > 0)).reshape(n, rotations)
  assert [o.shape for o in case.objects][-1] == 'cylinder'
  assert not lifted[:-1].any(), f'lifted at rotations: {[np.flatnonzero(r) for r in lifted]}'
  assert lifted[-1].sum() >= rotations - 1
