"""Case files from the outside world: any file either loads into a case with finite values inside
the physical bounds, or fails with one ScenarioError naming the file (and the line); fuzzed over
1,200 generated files of both formats. Objects that interpenetrate as placed are named."""
import math
import os
import random

import numpy as np
import pytest

from mvcoba_jax.config import resolve
from mvcoba_jax.sim.scenarios import OCCLUDER_REACH, ScenarioError, overlaps, read_case
from mvcoba_jax.sim.tabletop import Tabletop

HALF, TOP = 0.224, 0.4
SCN_LINES = ('cube red 0.02 -0.05 30', 'flat_box #336699 0.1 0.1 0', 'cube blue 0.1 0.1 45 0.052',
             'arch green -0.1 0.05 90', 'occluder 0 0.3 0.0 0.15 90', 'occluder 1 -0.3 0.1 0.1 0',
             '# a comment', '', 'disk pink 0 0 0 # trailing comment')
VPG_LINES = ('4.obj 0.1 0.2 0.3 -0.5 0.0 0.026 0 0 0', '0.obj 0.3 0.4 0.6 -0.6 -0.1 0.025 0 0 1.5',
             '8.obj 0.6 0.4 0.3 -0.4 0.1 0.026 1.57 0 0', '3.obj 0.5 0.5 0.5 -0.89 -0.39 0.026 0 0 0')
NASTY = ('nan', 'NaN', 'inf', '-inf', '1e300', '-1e300', '1e39', '-1e39', '1e-400', '0x1p3', '',
         'é', '\x0c', '\u2028', '\u00a0', '١', '1_0', '0', '-0', '1e3', '0.5', '-0.5', '360',
         '2e40', 'cube', 'occluder', '#', '# x', '9', '-1', '99999999999999999999', 'red',
         '#zzzzzz', '\t', '\r', 'obj', '5.obj', '4.obj', '0.224', '0.2241', '0.4', '0.41')


def _mutate(rng: random.Random, line: str) -> str:
  fields = line.split(' ')
  roll = rng.random()
  if roll < 0.5 and fields:
    fields[rng.randrange(len(fields))] = rng.choice(NASTY)
  elif roll < 0.65 and fields:
    del fields[rng.randrange(len(fields))]
  elif roll < 0.8:
    fields.insert(rng.randrange(len(fields) + 1), rng.choice(NASTY))
  elif roll < 0.9:
    return line + rng.choice(('\r', '\x0c', '\u2028', '\x00', '\u0085'))
  else:
    return ''.join(rng.choice(line + '\n\t #.-') for _ in line)
  return ' '.join(fields)


def _fuzzed_files(folder, count=1200, seed=0):
  rng = random.Random(seed)
  for i in range(count):
    vpg = rng.random() < 0.4
    lines = [rng.choice(VPG_LINES if vpg else SCN_LINES) for _ in range(rng.randint(0, 6))]
    lines = [_mutate(rng, line) if rng.random() < 0.5 else line for line in lines]
    path = folder / f'case{i:04d}{".txt" if vpg else ".scn"}'
    data = '\n'.join(lines).encode()
    if rng.random() < 0.05:  # bytes that are no UTF-8
      data = data[:rng.randint(0, len(data))] + bytes([rng.randint(0x80, 0xff)]) + data
    path.write_bytes(data)
    yield path


def _check_loaded(case):
  for obj in case.objects:
    x, y, z = obj.pos
    assert all(math.isfinite(v) for v in (*obj.pos, *obj.quat, *obj.color)), obj
    assert abs(x) <= HALF + 1e-9 and abs(y) <= HALF + 1e-9 and 0.0 < z <= TOP + 1e-9, obj
    assert abs(np.linalg.norm(obj.quat) - 1.0) < 1e-5, obj
  for occ in case.occluders:
    x, y, z = occ.pos
    assert max(abs(x), abs(y)) > HALF and max(abs(x), abs(y)) <= OCCLUDER_REACH, occ
    assert 0.0 < z <= OCCLUDER_REACH and math.isfinite(occ.yaw), occ


def test_fuzzed_case_files_load_in_bounds_or_fail_naming_the_file(tmp_path):
  outcomes = {'loaded': 0, 'refused': 0}
  for path in _fuzzed_files(tmp_path):
    try:
      case = read_case(path)
    except ScenarioError as e:
      assert str(e).startswith(f'{path}:'), str(e)
      outcomes['refused'] += 1
    else:
      _check_loaded(case)
      outcomes['loaded'] += 1
  assert outcomes['loaded'] > 100 and outcomes['refused'] > 300, outcomes


@pytest.mark.parametrize('make, says', [
    (lambda p: p, 'cannot read the case file: No such file'),
    (lambda p: (p.mkdir(), p)[1], 'not a regular file'),
    (lambda p: (os.mkfifo(p), p)[1], 'not a regular file'),  # would block an open() forever
    (lambda p: (p.write_bytes(b'cube red 0 0 0\n\xff\xfe'), p)[1], ':2: not UTF-8 text'),
    (lambda p: (p.write_text(''), p)[1], 'holds no objects'),
    (lambda p: (p.write_text('cube red 0 0 0' + ' ' * 2_000_000), p)[1], 'at most'),
])
def test_unreadable_files_are_one_line_errors(tmp_path, make, says):
  path = make(tmp_path / 'case.scn')
  with pytest.raises(ScenarioError) as error:
    read_case(path)
  assert str(error.value).startswith(str(path)) and says in str(error.value)
  assert '\n' not in str(error.value)


def test_physical_bounds(tmp_path):
  def refused(text, field):
    path = tmp_path / 'c.scn'
    path.write_text(text)
    with pytest.raises(ScenarioError, match=f"c.scn:1: field '{field}'"):
      read_case(path)

  refused('cube red 0 0 0 0.5', 'z')  # above the workspace
  refused('cube red 0 0 0 1e39', 'z')
  refused('occluder 0 0.1 0.0 0.15 0\ncube red 0 0 0', 'x')  # inside the workspace
  refused('occluder 0 0.3 0.0 -0.1 0\ncube red 0 0 0', 'z')  # under the table
  refused('occluder 0 1e39 0.0 0.1 0\ncube red 0 0 0', 'x')
  path = tmp_path / 'yaw.scn'
  path.write_text('cube red 0 0 1e300\ncube red 0.1 0.1 30\x0c\u2028\ncube red -0.1 -0.1 0\n')
  case = read_case(path)  # any finite yaw is an angle; only \\n ends a line, as in editors
  assert all(np.isfinite(o.quat).all() for o in case.objects)
  assert [o.line for o in case.objects] == [1, 2, 3]
  path.write_text('cube red 0 0 0\u2028\nlego red 0 0 0\n')
  with pytest.raises(ScenarioError, match="yaw.scn:2: field 'shape'"):
    read_case(path)


def test_vpg_lines_outside_its_workspace_are_counted_and_named(tmp_path):
  path = tmp_path / 'parked.txt'
  path.write_text('4.obj 0.1 0.2 0.3 -1.5 0.0 0.026 0 0 0\n4.obj 0.1 0.2 0.3 -0.5 0.0 -0.5 0 0 0\n')
  with pytest.raises(ScenarioError, match=r'its 2 lines \(1, 2\) all lie outside'):
    read_case(path)
  path.write_text('4.obj 0.1 0.2 0.3 -1.5 0.0 0.026 0 0 0\n4.obj 0.1 0.2 0.3 -0.5 0.0 0.026 0 0 0\n')
  assert read_case(path).parked_lines == (1,)


def test_objects_placed_into_each_other_are_named_by_both_lines(tmp_path):
  env = Tabletop(resolve('default', ['scene.pool=cube:3,tall_box:1', 'env.num_objects=4']).tabletop)
  path = tmp_path / 'overlap.scn'
  path.write_text('cube red 0 0 0\ncube blue 0.02 0 0\ntall_box green 0.15 0.15 0\n')
  found = overlaps(read_case(path), env)
  assert len(found) == 1 and f'{path}:1 and line 2' in found[0]
  path.write_text('cube red 0 0 0\ncube blue 0.051 0 0\ncube green 0 0 0 0.077\n')  # touching
  assert overlaps(read_case(path), env) == []
  path.write_text('cube red 0.1 0.1 0\ncube blue 0.1 0.1 0\n')  # two alike at one spot
  (found,) = overlaps(read_case(path), env)
  assert f'{path}:1 and line 2: the objects are placed at one spot' in found


def test_a_case_of_too_many_objects_is_refused_naming_the_first_line_beyond(tmp_path):
  path = tmp_path / 'many.scn'
  path.write_text(''.join(f'cube red {0.0003 * i - 0.18:.4f} 0 0\n' for i in range(1200)))
  with pytest.raises(ScenarioError, match='1200 objects; a case holds at most 128 .line 129'):
    read_case(path)


def test_mvcoba_authors_block_table(tmp_path):
  """Their 1.obj is the 5 cm cube (VPG's 1.obj is the 10 cm arch): a 2 x 3 grid at 5.7 cm pitch
  reads as six apart cubes with their table and as overlapping arches with VPG's, refused."""
  path = tmp_path / 'grid.txt'
  path.write_text(''.join(f'1.obj 0.1 0.2 0.3 {-0.5 + 0.057 * i:.3f} {0.057 * j:.3f} 0.026 0 0 0\n'
                          for i in range(2) for j in range(3)))
  env = Tabletop(resolve('default', ['scene.pool=cube:6,arch:6', 'env.num_objects=6']).tabletop)
  theirs = read_case(path, blocks='mvcoba')
  assert [o.shape for o in theirs.objects] == ['cube'] * 6
  assert overlaps(theirs, env) == []
  vpg = read_case(path)
  assert [o.shape for o in vpg.objects] == ['arch'] * 6
  assert any('interpenetrate' in m for m in overlaps(vpg, env))
  with pytest.raises(ScenarioError, match="unknown block table 'lego'"):
    read_case(path, blocks='lego')


def test_an_error_about_a_huge_field_is_one_short_line(tmp_path):
  path = tmp_path / 'huge.scn'
  path.write_text('cube red ' + 'x' * 100_000 + ' 0 0\n')
  with pytest.raises(ScenarioError) as error:
    read_case(path)
  assert len(str(error.value)) <= 300 and "huge.scn:1: field 'x'" in str(error.value)


@pytest.mark.parametrize('char', ['\r', '\x0c', '\x0b', '\u2028', '\x85', '\x1c', '\x1e'])
def test_odd_line_breaks_inside_a_line_keep_the_line_numbers(tmp_path, char):
  path = tmp_path / 'odd.scn'
  path.write_bytes(f'cube red 0 0 0\ncube{char}red 0 0\n'.encode())
  with pytest.raises(ScenarioError, match=r'odd.scn:2: '):
    read_case(path)
