"""Objects from mesh files on the real physics of each backend: a 5 cm cube written as an .obj
rests, is seen and is grasped as the procedural cube is; an L-shaped .obj, split by CoACD, rests
on both legs with its notch empty."""
import json
import time

import jax
import numpy as np
import pytest
import trimesh

from mvcoba_jax.cli import eval as eval_cli
from mvcoba_jax.sim import cameras, meshes
from mvcoba_jax.sim.primitives import GRASP
from tests.helpers import BACKENDS, actions, layout, make_env, stack

CUBE, MESH_CUBE, ELL = 0, 1, 2
AT = {CUBE: (-0.08, -0.08), MESH_CUBE: (0.08, -0.08), ELL: (0.0, 0.08)}


@pytest.fixture(scope='module')
def files(tmp_path_factory):
  folder = tmp_path_factory.mktemp('meshes')
  trimesh.creation.box((0.05, 0.05, 0.05)).export(folder / 'cube.obj')
  # An L, 2 cm thick and 2 cm tall: legs of 8 cm along x and y from the corner.
  leg = trimesh.creation.box((0.08, 0.02, 0.02))
  leg.apply_translation((0.04, 0.01, 0.0))
  other = trimesh.creation.box((0.02, 0.06, 0.02))
  other.apply_translation((0.01, 0.05, 0.0))
  trimesh.util.concatenate([leg, other]).export(folder / 'ell.obj')
  return folder


@pytest.fixture(scope='module', params=BACKENDS)
def env(request, files):
  return make_env('tiny', request.param,
                  f'scene.pool=cube:1,{files / "cube.obj"}:1,{files / "ell.obj"}:1',
                  'scene.max_geom_pairs=16', 'scene.max_contact_points=64')


@pytest.fixture(scope='module')
def outcome(env):
  scene = layout(env, [(slot, *xy, 0.0) for slot, xy in AT.items()])
  start = jax.jit(jax.vmap(env.reset_from_case))(stack([scene, scene]))
  grasps = actions([(GRASP, 0, *AT[CUBE], 0.05), (GRASP, 0, *AT[MESH_CUBE], 0.05)])
  end, info = jax.jit(jax.vmap(env.step))(start, grasps)
  return start, end, info


def test_the_ell_is_split_into_convex_parts(env):
  ell = env.scene.index.slot_shapes[ELL]
  assert ell.endswith('ell.obj')
  assert np.sum(env.scene.index.geom_slot == ELL) >= 2


def test_a_mesh_cube_rests_as_the_procedural_cube(env, outcome):
  start, _, _ = outcome
  z = np.asarray(start.sim.qpos)[0, env.scene.index.slot_qpos + 2]
  assert abs(z[MESH_CUBE] - z[CUBE]) < 0.001 and abs(z[CUBE] - 0.025) < 0.002, z
  assert abs(z[ELL] - 0.01) < 0.002, z  # on the table, not on a hull over its notch


def test_cameras_see_the_tops_of_mesh_objects(env, outcome):
  start, _, _ = outcome
  images = cameras.render(env, jax.tree.map(lambda x: x[0], start))
  points = np.concatenate([np.asarray(i.points).reshape(-1, 3) for i in images])
  geom = np.concatenate([np.asarray(i.geom).ravel() for i in images])
  slot = np.where(geom >= 0, env.scene.index.geom_slot[np.maximum(geom, 0)], -1)
  for s, top in ((CUBE, 0.05), (MESH_CUBE, 0.05), (ELL, 0.02)):
    assert abs(points[slot == s, 2].max() - top) < 0.002, (s, points[slot == s, 2].max())
  # Straight above the notch of the L, 3 cm in from its corner along both legs, lies the table.
  notch = np.asarray(AT[ELL]) + 0.0  # the L's frame is its bounding box's centre
  near = np.linalg.norm(points[:, :2] - (notch + 0.01), axis=1) < 0.005
  assert near.any() and np.all(slot[near] == -1) and np.all(points[near, 2] < 0.002)


def test_the_scripted_grasp_lifts_both_cubes(outcome):
  _, end, info = outcome
  assert np.asarray(info.grasp_success).tolist() == [True, True]
  assert np.asarray(info.healthy).all()


def test_a_split_mesh_is_read_from_the_cache_the_second_time(files):
  """CoACD's parts are kept by the file's content hash: read again, in well under a second."""
  ell = str(files / 'ell.obj')
  first = meshes.parts(ell)
  meshes.parts.cache_clear()
  began = time.perf_counter()
  again = meshes.parts(ell)
  assert time.perf_counter() - began < 1.0
  assert len(again) == len(first) >= 2 and all(np.array_equal(a, b) for a, b in zip(first, again))


def test_heuristic_evaluates_a_case_file_with_mesh_lines(files, tmp_path):
  """`mvcoba-eval --baseline heuristic --suite CASE.scn` with a mesh line, its path relative to
  the case file."""
  case = files / 'mixed.scn'
  case.write_text('cube.obj red 0.05 0.0 0\ncube blue -0.08 0.05 0\n')
  out = tmp_path / 'out'
  assert eval_cli.main(['--baseline', 'heuristic', '--suite', str(case), '--config', 'tiny',
                        '--runs', '1', '--max-actions', '4', '--out', str(out)]) == 0
  runs = json.loads((out / 'results.json').read_text())[str(case)]['baseline:heuristic']['runs']
  (run,) = runs['mixed']
  assert run['objects'] == 2 and run['grasp_successes'] >= 1
