"""Case files: our format round-trips, bad lines name file/line/field, VPG cases load resting.

No physics: layouts are checked on the host and overlaps with native MuJoCo collision detection.
"""
import dataclasses
import math
import pathlib

import mujoco
import numpy as np
import pytest

from mvcoba_jax.config import resolve
from mvcoba_jax.suites.cases import case_problems, pool_for, settled_starts, suite_config
from mvcoba_jax.suites.visibility import visibility
from mvcoba_jax.sim import arrangements, meshes, occluders, procedural, shapes
from mvcoba_jax.sim.geometry import quat_mul, yaw_quat
from mvcoba_jax.sim.scenarios import (
  Case,
  CaseObject,
  ScenarioError,
  case_to_layout,
  half_height,
  read_case,
  stack_layouts,
  write_scenario,
)
from mvcoba_jax.sim.scene import GRIPPER_PARK, park_position
from mvcoba_jax.sim.tabletop import Tabletop
from mvcoba_jax.suites import SUITES, SUITES_DIR, generate, novel, suite_files
from tests.penetration import max_penetration

VPG_CASES = SUITES_DIR / 'vpg'
VPG_COUNTS = (4, 5, 3, 5, 5, 6, 3, 6, 6, 5, 4)

SCN = """\
# a little case
cube     red      0.020  -0.050   30
flat_box #4e79a7  0.000   0.100   -90.5     # a comment
octagon  #0a0b0c -0.100   0.000   0
cube     blue     0.000   0.100   45       0.060
occluder 1 0.30000 0.00000 0.15000 90
"""


def write(tmp_path, name, text):
  path = tmp_path / name
  path.write_text(text)
  return path


def rotation(quat) -> np.ndarray:
  rot = np.zeros(9)
  mujoco.mju_quat2Mat(rot, np.asarray(quat, float))
  return rot.reshape(3, 3)


def three_cubes(occluders=()):
  """Tiny scene with exactly three cube slots (building it compiles nothing)."""
  config = resolve('tiny', ['scene.pool=cube:3'])
  return dataclasses.replace(config, scene=dataclasses.replace(config.scene, occluders=occluders))


@pytest.fixture(scope='module')
def tiny():
  return Tabletop(three_cubes().tabletop)


# ------------------------------------------------------------------------------ our format
def test_reads_our_format(tmp_path):
  case = read_case(write(tmp_path, 'a.scn', SCN))
  assert case.name == 'a' and [o.line for o in case.objects] == [2, 3, 4, 5]
  cube, flat, octagon, top = case.objects
  np.testing.assert_allclose(cube.color, shapes.COLORS[6], atol=1e-6)
  np.testing.assert_allclose(flat.color, (0x4e / 255, 0x79 / 255, 0xa7 / 255))
  np.testing.assert_allclose(cube.pos, (0.02, -0.05, 0.026))
  np.testing.assert_allclose(cube.quat, (math.cos(math.pi / 12), 0, 0, math.sin(math.pi / 12)),
                             atol=1e-6)
  # The octagon rests in its rest_quat (axis vertical), turned about z.
  rest = shapes.SHAPES['octagon']
  np.testing.assert_allclose(octagon.pos[2], 0.5 * rest.rest_extent[2] + 0.001)
  np.testing.assert_allclose(octagon.quat, rest.rest_quat, atol=1e-6)
  assert top.pos[2] == 0.06
  (occ,) = case.occluders
  assert occ.slot == 1 and occ.pos == (0.3, 0.0, 0.15) and occ.line == 6
  np.testing.assert_allclose(occ.yaw, math.pi / 2)


def test_round_trip(tmp_path):
  case = read_case(write(tmp_path, 'a.scn', SCN))
  write_scenario(case, tmp_path / 'b.scn')
  again = read_case(tmp_path / 'b.scn')
  assert len(again.objects) == len(case.objects)
  for a, b in zip(case.objects, again.objects):
    assert a.shape == b.shape
    np.testing.assert_allclose(a.color, b.color, atol=1e-6)
    np.testing.assert_allclose(a.pos, b.pos, atol=1e-5)
    np.testing.assert_allclose(rotation(a.quat), rotation(b.quat), atol=1e-4)
  assert [(o.slot, o.pos) for o in again.occluders] == [(o.slot, o.pos) for o in case.occluders]
  np.testing.assert_allclose(again.occluders[0].yaw, case.occluders[0].yaw, atol=1e-5)


def test_writer_refuses_objects_off_their_rest_orientation(tmp_path):
  tipped = CaseObject('tall_box', (0.5, 0.5, 0.5), (0.0, 0.0, 0.026),
                      (math.sqrt(0.5), math.sqrt(0.5), 0.0, 0.0), 7)
  with pytest.raises(ScenarioError, match=r'c\.txt:7: .*rest orientation'):
    write_scenario(Case('c', 'c.txt', (tipped,)), tmp_path / 'c.scn')


@pytest.mark.parametrize('line, field, says', [
    ('cube red 0.0 0.0', 'yaw_deg', 'missing'),
    ('cube red 0 0 0 0.03 7', '#7', 'unexpected'),
    ('sphere red 0 0 0', 'shape', 'known: prism, arch'),
    ('cube teal 0 0 0', 'colour', "unknown colour 'teal'"),
    ('cube #12345 0 0 0', 'colour', 'unknown colour'),
    ('cube red abc 0 0', 'x', "'abc' is not a number"),
    ('cube red 0 nan 0', 'y', 'not finite'),
    ('cube red 0 0 inf', 'yaw_deg', 'not finite'),
    ('cube red 0.3 0 0', 'x', 'outside the workspace'),
    ('cube red 0 -0.23 0', 'y', 'outside the workspace'),
    ('cube red 0 0 0 0.01', 'z', 'into the table'),
    ('occluder 1.5 0.3 0 0.1 0', 'slot', 'not an integer'),
    ('occluder -1 0.3 0 0.1 0', 'slot', 'negative'),
    ('occluder 0 0.3 0 0.1', 'yaw_deg', 'missing'),
    ('occluder 0 0.3 0 zz 0', 'z', 'not a number'),
    ('occluder 2 0.3 0 0.1 0', 'slot', 'already placed on line 2'),
])
def test_bad_line_names_file_line_and_field(tmp_path, line, field, says):
  path = write(tmp_path, 'bad.scn', f'# header\noccluder 2 0.3 0 0.1 0\n{line}\ncube red 0 0 0\n')
  with pytest.raises(ScenarioError) as err:
    read_case(path)
  message = str(err.value)
  assert f'{path}:3: field {field!r}' in message and says in message, message


def test_workspace_is_a_parameter(tmp_path):
  path = write(tmp_path, 'w.scn', 'cube red 0.2 0 0\n')
  assert read_case(path).objects[0].pos[0] == 0.2
  with pytest.raises(ScenarioError, match=r"w\.scn:1: field 'x'"):
    read_case(path, workspace_half=0.1)


def test_empty_case_and_unknown_extension(tmp_path):
  with pytest.raises(ScenarioError, match='no objects'):
    read_case(write(tmp_path, 'e.scn', '# nothing\n\noccluder 0 0.3 0 0.1 0\n'))
  with pytest.raises(ScenarioError, match=r"\.json"):
    read_case(write(tmp_path, 'e.json', 'cube red 0 0 0\n'))


# ------------------------------------------------------------------------------ VPG's format
def vpg_line(mesh, x, y, z, a, b, c, rgb=(0.3, 0.4, 0.5)):
  return ' '.join(str(v) for v in (mesh, *rgb, x, y, z, a, b, c))


def test_vpg_reader(tmp_path):
  path = write(tmp_path, 'v.txt', '\n'.join([
      vpg_line('4.obj', -0.45, 0.05, 0.026, 0.0, 0.0, 0.3),  # resting as given
      vpg_line('4.obj', -0.89, -0.39, 0.026, 0.0, 0.0, 0.0),  # parked beside the workspace
      vpg_line('4.obj', -0.60, -0.10, 0.026, 0.5, 0.7, 0.2),  # angles give a tilted cube
      vpg_line('3.obj', -0.50, 0.15, 0.0135, math.pi / 2, 0.0, 0.4),  # angles: on its side
      vpg_line('6.obj', -0.60, 0.00, -726.0, 0.1, 0.2, 0.3),  # parked under the table
      vpg_line('1.obj', -0.35, -0.15, 0.026, 0.0, -math.pi / 2, 0.0),  # arch, import-turned
  ]) + '\n')
  case = read_case(path)
  assert [o.line for o in case.objects] == [1, 3, 4, 6]
  assert [o.shape for o in case.objects] == ['cube', 'cube', 'flat_box', 'arch']
  z_vpg = (0.026, 0.026, 0.0135, 0.026)
  for obj, z, (x, y) in zip(case.objects, z_vpg, [(0.05, 0.05), (-0.1, -0.1), (0.0, 0.15),
                                                  (0.15, -0.15)]):
    np.testing.assert_allclose(obj.pos[:2], (x, y), atol=1e-12)
    h = half_height(obj.shape, obj.quat)
    assert abs(h - z) <= 0.003 and obj.pos[2] == pytest.approx(h + 0.001)
    assert obj.color == (0.3, 0.4, 0.5)
  # The tilted cube now rests on a face.
  assert np.isclose(np.abs(rotation(case.objects[1].quat)[2]), 1.0, atol=1e-9).sum() == 1
  # The flat box lies flat and keeps the yaw of its long side (mesh x), which R puts along +x.
  flat = rotation(case.objects[2].quat)
  np.testing.assert_allclose(abs(flat[2, 2]), 1.0, atol=1e-9)
  np.testing.assert_allclose(flat[:, 0], (1.0, 0.0, 0.0), atol=1e-9)
  # R stands the arch on end (mesh x up); the import turn makes that the arch upright.
  np.testing.assert_allclose(rotation(case.objects[3].quat)[:, 2], (0, 0, 1), atol=1e-9)


@pytest.mark.parametrize('line, field, says', [
    ('4.obj 0.3 0.4 0.5 -0.5 0.0 0.026 0.0 0.0', 'euler_c', 'missing'),
    ('5.obj 0.3 0.4 0.5 -0.5 0.0 0.026 0.0 0.0 0.0', 'mesh', "unknown mesh '5.obj'"),
    ('4.obj 0.3 0.4 0.5 -0.5 0.0 zz 0.0 0.0 0.0', 'z', "'zz' is not a number"),
    ('4.obj 0.3 0.4 0.5 -0.5 0.0 0.026 nan 0.0 0.0', 'euler_a', 'not finite'),
    ('4.obj 0.3 0.4 2.5 -0.5 0.0 0.026 0.0 0.0 0.0', 'blue', 'not in 0..1'),
])
def test_bad_vpg_line_names_file_line_and_field(tmp_path, line, field, says):
  good = vpg_line('4.obj', -0.5, 0.0, 0.026, 0.0, 0.0, 0.0)
  path = write(tmp_path, 'bad.txt', f'{good}\n{line}\n')
  with pytest.raises(ScenarioError) as err:
    read_case(path)
  message = str(err.value)
  assert f'{path}:2: field {field!r}' in message and says in message, message


@pytest.fixture(scope='module')
def public_cases():
  return [read_case(VPG_CASES / f'test-10-obj-{i:02d}.txt') for i in range(len(VPG_COUNTS))]


def test_public_vpg_cases_rest_at_their_heights(public_cases):
  assert tuple(len(c.objects) for c in public_cases) == VPG_COUNTS
  off = set()
  for case in public_cases:
    lines = pathlib.Path(case.path).read_text().splitlines()
    for obj in case.objects:
      z = float(lines[obj.line - 1].split()[6])
      h = half_height(obj.shape, obj.quat)
      assert obj.pos[2] >= h + 0.001 - 1e-9  # nothing starts in the table
      if abs(h - z) > 0.003:
        off.add((case.name[-2:], obj.line, obj.shape))
        if obj.shape == 'cylinder':  # lies on another object: keeps its height
          assert obj.pos[2] == z
  # No octagon face is 5 cm high: VPG's standing octagons are listed 4.3 mm lower than ours
  # rest. The cylinder of case 09 lies on other objects (checked for overlaps below).
  assert off == {('05', 7, 'octagon'), ('07', 7, 'octagon'), ('09', 7, 'octagon'),
                 ('10', 7, 'octagon'), ('09', 3, 'cylinder')}


def deepest_overlap(env, layout) -> float:
  """Deepest contact (m) between the objects of `layout` and the table, as placed (no physics)."""
  idx = env.scene.index
  qpos = env.scene.mj_model.qpos0.copy()
  qpos[idx.gripper_qpos[:3]] = GRIPPER_PARK
  for i, adr in enumerate(idx.slot_qpos):
    qpos[adr:adr + 7] = np.concatenate([layout.pos[i], layout.quat[i]])
  return max_penetration(env, qpos)


def test_public_vpg_cases_do_not_interpenetrate(public_cases):
  env = Tabletop(resolve('default').tabletop)
  layouts = [case_to_layout(c, env) for c in public_cases]
  batch = stack_layouts(layouts)
  assert batch.pos.shape == (len(layouts), env.num_slots, 3)
  for case, layout in zip(public_cases, layouts):
    deepest = deepest_overlap(env, layout)
    assert deepest < 0.002, (case.name, deepest)


# ------------------------------------------------------------------------------ shipped suites
# suite -> (cases, fewest objects, most objects), the isolated one left out
SHIPPED = {'dev-random': (6, 20, 40), 'dev-ordered': (6, 4, 17), 'dev-occluded': (12, 3, 6),
           'random': (6, 20, 40), 'ordered': (8, 3, 16), 'packed-ring': (4, 3, 16),
           'packed-t_shape': (4, 3, 16), 'packed-stack': (4, 3, 16), 'occluded': (12, 3, 7)}


def heap_texts(suite: str, seeds) -> list[str]:
  """The heaps as `generate.random_case` writes them from the draws each file says were passed
  over, case i from one of `seeds(i)`: the placement is NumPy alone, so this does not depend on
  the physics that chose the draws (that the heaps stay on the table is tested below)."""
  texts = []
  for i, path in enumerate(sorted((SUITES_DIR / suite).glob('*.scn'))):
    lines = path.read_text().splitlines()
    skip = frozenset(int(d) for line in lines if line.startswith('# draws passed over:')
                     for d in line.split(':')[1].split())
    objects = sum(1 for line in lines if not line.startswith('#')) - 1  # the isolated one
    draws = [generate.random_case(objects, seed, skip)[0] for seed in seeds(i)]
    texts.append(path.read_text() if path.read_text() in draws else draws[0])
  return texts


def drawn_texts(suite: str, draw, first: int = 0, tries: int = 20) -> list[str]:
  """Case files `first` on of a suite as the generator writes them, case i the draw
  `draw(try, i)` its file holds among the first `tries` (which draws pass is physics: tested
  below, on the physics)."""
  texts = []
  for i, path in enumerate(sorted((SUITES_DIR / suite).glob('*.scn'))[first:]):
    draws = [draw(t, i) for t in range(tries)]
    texts.append(path.read_text() if path.read_text() in draws else draws[0])
  return texts


@pytest.fixture(scope='module')
def generated():
  sealed = generate.SEALED_SEED
  training = arrangements.TRAINING
  return {
      'dev-random': heap_texts('dev-random', lambda i: [i]),
      'dev-ordered': generate.ordered_cases(),
      'dev-occluded': generate.set_occluded_cases() + drawn_texts(
          'dev-occluded', lambda t, i: generate.drawn_occluded_case(
              occluders.TEST, generate.OCCLUDED_SEED + 100 * t + i, i), first=3),
      'random': heap_texts('random', lambda i: [sealed + 100 * t + i for t in range(20)]),
      'ordered': drawn_texts('ordered', lambda t, i: generate.family_case(
          training[i % len(training)], sealed + 1000 + 100 * t + i)),
      **{f'packed-{kind}': drawn_texts(f'packed-{kind}', lambda t, i, k=k, kind=kind:
                                       generate.family_case(kind, sealed + 3000 + 1000 * k
                                                            + 100 * t + i))
         for k, kind in enumerate(arrangements.HELD_OUT)},
      'occluded': drawn_texts('occluded', lambda t, i: generate.drawn_occluded_case(
          occluders.TEST, sealed + 7000 + 100 * t + i, i), tries=generate.SEALED_TRIES),
  }


@pytest.mark.parametrize('suite', sorted(SHIPPED))
def test_shipped_suites_are_generated_and_start_apart(suite, generated):
  """The files are what `python -m mvcoba_jax.suites.generate` writes, with the issue's case and object counts;
  every object (the isolated one too) starts clear of the others and of the table."""
  texts = generated[suite]
  files = sorted((SUITES_DIR / suite).glob('*.scn'))
  assert [f.read_text() for f in files] == texts, 'run python -m mvcoba_jax.suites.generate'
  cases = [read_case(f) for f in files]
  n_cases, fewest, most = SHIPPED[suite]
  assert len(cases) == n_cases
  assert all(fewest + 1 <= len(c.objects) <= most + 1 for c in cases)  # + the isolated object
  env = Tabletop(suite_config(resolve('default'), pool_for(cases)).tabletop)
  for case in cases:
    deepest = deepest_overlap(env, case_to_layout(case, env))
    assert deepest < 0.002, (case.name, deepest)


def test_the_novel_suite_is_generated_from_the_held_out_objects_alone():
  """novel/ is what `python -m mvcoba_jax.suites.novel` writes (heaps and packed rows drawn by
  NumPy from its seeds; which draw passed is physics, tested below): everyday objects only, none
  of which any training pool or validation case holds."""
  files = sorted((SUITES_DIR / 'novel').glob('*.scn'))
  cases = [read_case(f) for f in files]
  everyday = novel.objects(novel.EVERYDAY)
  assert [len(c.objects) for c in cases[:4]] == list(novel.HEAPS) and len(cases) == 8
  named = {meshes.absolute(o) for o in everyday}  # as case files and configs name them
  assert {o.shape for c in cases for o in c.objects} <= named
  relative = lambda text: text.replace(str(procedural.OBJECTS), '../../sim/objects').replace(
      'mvcoba_jax.suites.generate', 'mvcoba_jax.suites.novel')
  for i, (path, n) in enumerate(zip(files, novel.HEAPS)):
    skip = frozenset(int(d) for line in path.read_text().splitlines()
                     if line.startswith('# draws passed over:') for d in line.split(':')[1].split())
    draws = [relative(generate.random_case(n, novel.NOVEL_SEED + 100 * t + i, skip, pool=tuple(
        everyday), isolated=False)[0]) for t in range(5)]
    assert path.read_text() in draws, path.name
  members = [o for o in everyday if pathlib.Path(o).name in novel.PACKABLE_EVERYDAY]
  for i, path in enumerate(files[4:]):
    draws = [relative(novel.packed(members, novel.NOVEL_SEED + 50 + 100 * t + i))
             for t in range(5)]
    assert path.read_text() in draws, path.name
  training = {n for n, _ in resolve('objects').scene.pool}
  assert not training & named


@pytest.mark.parametrize('suite', ['random', 'dev-random', 'novel'])
def test_random_heaps_stay_on_the_table(suite):
  """Every object of every heap stays in the workspace while the case settles as mvcoba-eval
  starts its runs (its jitters, two runs)."""
  cases = [read_case(f) for f in sorted((SUITES_DIR / suite).glob('*.scn'))]
  _, states = settled_starts(cases, resolve('default'), 2)
  in_play = np.asarray(states.in_play).reshape(len(cases), 2, -1).sum(axis=-1)
  listed = np.array([len(c.objects) for c in cases])
  assert (in_play == listed[:, None]).all(), dict(zip([c.name for c in cases], in_play.tolist()))


# ------------------------------------------------------------------------------ layouts
def test_case_to_layout(tmp_path, tiny):
  case = read_case(write(tmp_path, 'l.scn', 'cube red 0.02 -0.05 30\ncube #0a0b0c 0 0.1 0\n'))
  layout = case_to_layout(case, tiny)
  assert layout.in_play.tolist() == [True, True, False]
  np.testing.assert_allclose(layout.pos[:2], [o.pos for o in case.objects], atol=1e-6)
  np.testing.assert_allclose(layout.quat[0], case.objects[0].quat, atol=1e-6)
  np.testing.assert_allclose(layout.pos[2], park_position(2))
  np.testing.assert_allclose(layout.quat[2], (1, 0, 0, 0))
  np.testing.assert_allclose(layout.color[1], (10 / 255, 11 / 255, 12 / 255), atol=1e-6)
  np.testing.assert_allclose(layout.color[2], (0.5, 0.5, 0.5))
  assert layout.occluder_pos.shape == (0, 3)
  batch = stack_layouts([layout, layout])
  assert batch.in_play.shape == (2, 3) and batch.occluder_quat.shape == (2, 0, 4)


def test_case_to_layout_names_missing_slots(tmp_path, tiny):
  four = read_case(write(tmp_path, 'four.scn', 'cube red 0 0 0\n' * 4 + 'disk red 0.1 0 0\n'))
  with pytest.raises(ScenarioError) as err:
    case_to_layout(four, tiny)
  message = str(err.value)
  assert 'four.scn' in message and 'scene.pool' in message
  assert "4 'cube' slots and the pool has 3" in message
  assert "1 'disk' slots and the pool has 0" in message
  occluded = read_case(write(tmp_path, 'o.scn', 'cube red 0 0 0\noccluder 0 0.3 0 0.1 0\n'))
  with pytest.raises(ScenarioError, match=r"o\.scn:2: field 'slot': .* out of range"):
    case_to_layout(occluded, tiny)


def test_case_to_layout_places_occluders(tmp_path):
  env = Tabletop(three_cubes(occluders=((0.01, 0.1, 0.1), (0.01, 0.1, 0.1))).tabletop)
  case = read_case(write(tmp_path, 'o.scn', 'cube red 0 0 0\noccluder 1 0.3 0 0.1 90\n'))
  layout = case_to_layout(case, env)
  parked_pos, parked_quat = env.parked_occluders()
  np.testing.assert_allclose(layout.occluder_pos[0], parked_pos[0])
  np.testing.assert_allclose(layout.occluder_quat[0], parked_quat[0])
  np.testing.assert_allclose(layout.occluder_pos[1], (0.3, 0.0, 0.1), atol=1e-6)
  np.testing.assert_allclose(layout.occluder_quat[1], yaw_quat(math.pi / 2), atol=1e-6)
  np.testing.assert_allclose(layout.quat[0], quat_mul(yaw_quat(0.0), np.array([1.0, 0, 0, 0])))


ONE_CAMERA_ONLY = {'occluded': 9, 'dev-occluded': 12}  # cases with an object one camera alone sees


@pytest.mark.parametrize('suite', ['occluded', 'dev-occluded'])
def test_every_object_of_the_occluded_suites_is_seen_by_a_camera(suite):
  """The occluded suites test the fusion of two views: at the start each object shows at least
  half of itself to one camera, some to one camera only (in dev-occluded, camera 1 sees nothing
  in case 00)."""
  cases = [read_case(f) for f in sorted((SUITES_DIR / suite).glob('*.scn'))]
  rows = visibility(cases, resolve('default'))
  assert len(rows) == 12 and [r['seen_by_none'] for r in rows] == [[]] * 12
  assert sum(bool(r['seen_by_one_only']) for r in rows) >= ONE_CAMERA_ONLY[suite]
  if suite == 'dev-occluded':
    assert all(o['visible_fraction'][0] == 0.0 for o in rows[0]['objects'])


def test_the_high_validation_occluders_hide_as_much_as_the_tests():
  """val-occluded-high, the occluded suite for choosing settings, leaves each object seen by a
  camera and at least as large a share (57 of 67 in the test's) seen by one camera only."""
  folder = pathlib.Path(__file__).resolve().parents[2] / 'docs/results/validation/val-occluded-high'
  cases = [read_case(f) for f in sorted(folder.glob('*.scn'))]
  rows = visibility(cases, resolve('default'))
  one = sum(len(r['seen_by_one_only']) for r in rows)
  assert len(rows) == 6 and [r['seen_by_none'] for r in rows] == [[]] * 6
  assert one / sum(len(c.objects) for c in cases) >= 57 / 67


def test_shipped_cases_pass_the_load_check():
  """No shipped case holds objects that interpenetrate as placed."""
  for suite in SUITES:
    cases = [read_case(f) for f in suite_files([suite])[suite]]
    assert case_problems(cases, resolve('default')) == [], suite


# ------------------------------------------------------------------------------ fitting overlaps
def test_fit_overlaps_lifts_a_sunk_object_and_nudges_a_side_by_side_one(tmp_path):
  """Overlaps of known depth: a cube sunk 8 mm into the cube below is lifted, a cube placed 6 mm
  into its neighbour is moved sideways, each by the least distance that leaves no more than the
  load check's tolerance; objects listed before them do not move."""
  from mvcoba_jax.sim.scenarios import OVERLAP_TOLERANCE, fit_overlaps, overlaps
  path = tmp_path / 'overlapping.scn'
  path.write_text('cube red 0.0 0.0 0\n'
                  'cube blue 0.0 0.0 0 0.068\n'        # on top would be z = 0.076
                  'cube green 0.1 0.0 0\n'
                  'cube yellow 0.144 0.0 0\n')         # apart would be x >= 0.150
  case = read_case(path)
  env = Tabletop(suite_config(resolve('default'), pool_for([case])).tabletop)
  assert len(overlaps(case, env)) == 2
  fitted, moves = fit_overlaps(case, env)
  lift, nudge = 0.008 - OVERLAP_TOLERANCE, 0.006 - OVERLAP_TOLERANCE
  np.testing.assert_allclose(moves, [0.0, lift, 0.0, nudge], atol=2e-4)
  before, after = (np.array([o.pos for o in c.objects]) for c in (case, fitted))
  np.testing.assert_allclose(after - before, [[0, 0, 0], [0, 0, moves[1]], [0, 0, 0],
                                              [moves[3], 0, 0]], atol=2e-4)
  assert overlaps(fitted, env) == [] and case_problems([fitted], resolve('default')) == []
  with pytest.raises(ScenarioError, match=r'overlapping.scn:2: the cube would move more than 4 mm'):
    fit_overlaps(case, env, bound=0.004)


def test_fit_overlaps_leaves_a_valid_case_as_it_is(public_cases):
  from mvcoba_jax.sim.scenarios import fit_overlaps
  env = Tabletop(suite_config(resolve('default'), pool_for(public_cases)).tabletop)
  for case in public_cases[:3]:
    assert fit_overlaps(case, env) == (case, (0.0,) * len(case.objects))


def test_overlaps_of_another_block_table_are_named_as_its(tmp_path):
  """A VPG-format file written with the MV-COBA authors' mesh numbers (0.obj an octagon 25 mm
  thick) read with VPG's (0.obj a 93 mm prism): the load check says which table fits."""
  from mvcoba_jax.suites.cases import other_block_table
  lines = [f'0.obj 0.5 0.5 0.5 {-0.62 + 0.032 * i:.3f} 0.0 0.0313 0.0 0.0 0.0' for i in range(4)]
  path = tmp_path / 'authors-numbering.txt'
  path.write_text('\n'.join(lines) + '\n')
  config = resolve('default')
  assert case_problems([read_case(path, blocks='mvcoba')], config) == []
  assert case_problems([read_case(path, blocks='vpg')], config)
  hint = other_block_table([path], config, 'vpg')
  assert '--blocks vpg' in hint and 'likely mvcoba' in hint
  assert other_block_table([path], config, 'mvcoba') == ''
