"""Mesh objects as input: a case line or a pool entry naming a file that cannot be an object is
refused in one line naming the file and what is wrong, before anything compiles; a good file's
parts are centred on its bounding box, scaled, and capped in vertices."""
import numpy as np
import pytest
import trimesh

from mvcoba_jax.config import ConfigError, override, resolve
from mvcoba_jax.sim import everyday, grippers, meshes, procedural, shapes
from mvcoba_jax.sim.scenarios import ScenarioError, read_case


def _case(folder, shape_field):
  case = folder / 'case.scn'
  case.write_text(f'cube red 0.1 0.1 0\n{shape_field} blue 0.0 0.0 0\n')
  return case


def _refusal(folder, shape_field) -> str:
  with pytest.raises(ScenarioError) as error:
    read_case(_case(folder, shape_field))
  message = str(error.value)
  assert '\n' not in message and message.startswith(f'{folder / "case.scn"}:2: field \'shape\'')
  return message


def test_bad_mesh_files_are_refused_in_one_line(tmp_path, monkeypatch):
  (tmp_path / 'notes.txt').write_text('a mug\n')
  (tmp_path / 'garbage.obj').write_bytes(b'\x00\xff not a mesh \x01' * 10)
  (tmp_path / 'empty.obj').write_text('v 0 0 0\nv 1 0 0\nv 0 1 0\n')
  (tmp_path / 'flat.obj').write_text('v 0 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0.05 0.05 0\n'
                                     'f 1 2 3\nf 2 4 3\n')
  trimesh.creation.box((0.005, 0.005, 0.005)).export(tmp_path / 'crumb.obj')
  trimesh.creation.box((50, 50, 50)).export(tmp_path / 'millimetres.obj')
  trimesh.creation.box((0.6, 0.1, 0.1)).export(tmp_path / 'plank.obj')
  trimesh.creation.icosphere(subdivisions=2, radius=0.03).export(tmp_path / 'ball.obj')
  (tmp_path / 'no_parts').mkdir()
  (tmp_path / 'no_parts' / 'README').write_text('parts went missing\n')
  expected = {
      'missing.obj': 'no such mesh file or folder',
      'notes.txt': 'not a mesh file',
      'garbage.obj': 'holds no triangles',
      'empty.obj': 'holds no triangles',
      'flat.obj': 'degenerate',
      'crumb.obj': '5.0 mm across; an object is at least 10 mm',
      'millimetres.obj': 'objects are given in metres',
      'plank.obj': 'wider than the workspace',
      'no_parts/': 'a folder without parts',
      'ball.obj@x': "scale 'x' after @ is not a number",
  }
  for field, words in expected.items():
    assert words in _refusal(tmp_path, field), field
  monkeypatch.setattr(meshes, 'MAX_FACES', 100)
  assert '320 faces; a mesh holds at most 100' in _refusal(tmp_path, 'ball.obj')
  assert "unknown shape 'mug'" in _refusal(tmp_path, 'mug')


def test_a_pool_entry_that_is_no_object_is_a_config_error(tmp_path):
  with pytest.raises(ConfigError, match=r'^scene.pool: .*missing.obj: no such mesh file'):
    override(resolve('tiny'), f'scene.pool=cube:1,{tmp_path / "missing.obj"}:2')


def test_a_mesh_is_centred_scaled_and_capped_in_vertices(tmp_path):
  """A 50 mm box written in millimetres, off its origin, read at @0.001: a 5 cm cube centred on
  the origin; a fine sphere's hull keeps at most MAX_PART_VERTICES vertices, extremes included."""
  box = trimesh.creation.box((50.0, 50.0, 50.0))
  box.apply_translation((100.0, 0.0, 25.0))
  box.export(tmp_path / 'box_mm.stl')
  cube = shapes.shape(meshes.absolute('box_mm.stl@0.001', tmp_path))
  np.testing.assert_allclose(cube.extent, (0.05, 0.05, 0.05), atol=1e-6)
  (part,) = meshes.parts(cube.name)
  np.testing.assert_allclose(part.min(0), -part.max(0), atol=1e-6)
  trimesh.creation.icosphere(subdivisions=4, radius=0.04).export(tmp_path / 'ball.ply')
  (ball,) = meshes.parts(str(tmp_path / 'ball.ply'))
  assert len(ball) == meshes.MAX_PART_VERTICES
  np.testing.assert_allclose(ball.max(0) - ball.min(0), 0.08, atol=0.004)


def test_a_folder_of_parts_is_one_object(tmp_path):
  """Google Scanned Objects' layout: model_collision_*.obj beside a visual model.obj."""
  folder = tmp_path / 'table_top_toy'
  folder.mkdir()
  trimesh.creation.box((0.2, 0.2, 0.2)).export(folder / 'model.obj')  # visual: not collided
  for i, x in enumerate((-0.02, 0.02)):
    part = trimesh.creation.box((0.04, 0.03, 0.02))
    part.apply_translation((x, 0.0, 0.0))
    part.export(folder / f'model_collision_{i}.obj')
  toy = shapes.shape(str(folder))
  assert len(toy.parts) == 2
  np.testing.assert_allclose(toy.extent, (0.08, 0.03, 0.02), atol=1e-6)
  assert len(meshes.content_hash(str(folder))) == 64


def test_the_shipped_procedural_sets_are_what_the_generator_writes(tmp_path):
  for name, seed in procedural.SETS.items():
    procedural.write_set(tmp_path / name, procedural.SET_SIZE, seed)
    shipped = procedural.OBJECTS / name
    written = sorted(p.relative_to(tmp_path / name) for p in (tmp_path / name).rglob('*.*'))
    assert written == sorted(p.relative_to(shipped) for p in shipped.rglob('*.*'))
    for relative in written:
      assert (shipped / relative).read_bytes() == (tmp_path / name / relative).read_bytes()


def test_the_shipped_everyday_set_is_what_its_model_writes(tmp_path):
  everyday.write_set(tmp_path)
  shipped = procedural.OBJECTS / 'everyday'
  written = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob('*.*'))
  assert written == sorted(p.relative_to(shipped) for p in shipped.rglob('*.*'))
  assert all((shipped / r).read_bytes() == (tmp_path / r).read_bytes() for r in written)


def test_procedural_objects_are_grasp_sized():
  """Largest side 3-12 cm; the narrowest side of some part leaves the open fingers 4 cm."""
  for folder in sorted(procedural.OBJECTS.glob('*/[0-9]*')):
    shape = shapes.shape(str(folder))
    assert 0.03 <= max(shape.extent) <= 0.12, folder.name
    narrowest = min(min(np.ptp(np.asarray(p.vertices)[:, :2], axis=0)) for p in shape.parts)
    assert narrowest <= grippers.RG2.max_opening - 0.04, folder.name


def test_a_block_table_may_map_a_vpg_mesh_name_to_a_mesh(tmp_path, monkeypatch):
  """A VPG-format case whose `9.obj` is the user's own box, through a block table of their own;
  resting at its half height, as VPG files give it."""
  trimesh.creation.box((0.06, 0.04, 0.03)).export(tmp_path / 'box.obj')
  monkeypatch.setattr(shapes, 'BLOCK_TABLES', dict(shapes.BLOCK_TABLES))  # this test's own
  monkeypatch.chdir(tmp_path)
  shapes.add_block_table('lab', {'9.obj': 'box.obj', '4.obj': 'cube'})  # relative: made absolute
  case_file = tmp_path / 'lab.txt'
  case_file.write_text('9.obj 0.3 0.4 0.5 -0.45 0.05 0.015 0.0 0.0 0.0\n'
                       '4.obj 0.3 0.4 0.5 -0.55 -0.05 0.026 0.0 0.0 0.0\n')
  box, cube = read_case(case_file, blocks='lab').objects
  assert box.shape == str(tmp_path / 'box.obj') and cube.shape == 'cube'
  assert box.pos[2] == pytest.approx(0.015 + 0.001)
  with pytest.raises(meshes.MeshError, match="unknown shape 'lego'"):
    shapes.add_block_table('bad', {'5.obj': 'lego'})


def test_the_shipped_objects_are_named_inside_the_package(tmp_path, monkeypatch):
  """From any working folder, a path into the package's object sets is `package:...`, so a saved
  config that trained on them reads the same wherever the package is installed."""
  monkeypatch.chdir(tmp_path)
  mug = procedural.OBJECTS / 'everyday' / 'mug'
  for given in (str(mug), f'{mug}@1.5', 'package:sim/objects/everyday/mug'):
    name = shapes.reference(given)
    assert name.startswith('package:sim/objects/everyday/mug') and not name.startswith('/')
  assert shapes.shape('package:sim/objects/everyday/mug@1.5').extent[2] == pytest.approx(
      1.5 * shapes.shape('package:sim/objects/everyday/mug').extent[2])
