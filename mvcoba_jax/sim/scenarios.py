"""Test cases: our `.scn` text format, VPG's test-case files, and the layouts they start from.

Our format (`.scn`), one item per line; blank lines are ignored and `#` at the start of a line,
or `# ` after a field, starts a comment:

    # shape    colour   x       y       yaw_deg  [z]
    cube       red      0.020  -0.050   30
    flat_box   #336699  0.000   0.000   0
    cube       blue     0.000   0.000   45       0.052    # stacked on the flat box
    occluder   0        0.300   0.000   0.150    90       # occluder slot, x, y, z, yaw_deg

- shape: one of `shapes.SHAPE_NAMES`, or a mesh file or folder of convex parts, its path
  relative to the case file, with an optional scale (`mug.obj`, `scans/mug.stl@0.001`:
  `meshes`); it rests as the file has it, z up.
- colour: a VPG palette name (blue, green, brown, orange, yellow, gray, red, purple, cyan, pink)
  or `#rrggbb`.
- x, y: metres in the workspace frame (centre 0, 0); |x|, |y| must lie within the workspace.
- yaw_deg: degrees about z, applied to the shape's `rest_quat`.
- z: optional centre height for stacks; by default the object rests 1 mm above the table
  (z = half its rest height + 1 mm).
- `occluder <slot> <x> <y> <z> <yaw_deg>` places occluder slot `slot` (of `scene.occluders`).

VPG's format (`.txt`, `MESH R G B X Y Z A B C` in its robot frame, docs/usage.md): parked lines are skipped, x moves by +0.5 m, and each object gets a
resting orientation recovered from its Euler angles and height (see `_vpg_pose`).
"""
from __future__ import annotations

import collections
import dataclasses
import math
import os
import pathlib
import re
import stat

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from mvcoba_jax.sim import meshes, shapes
from mvcoba_jax.sim.config import Error
from mvcoba_jax.sim.geometry import euler_xyz_matrix, matrix_to_quat, quat_mul, yaw_quat
from mvcoba_jax.sim.scene import park_position
from mvcoba_jax.sim.tabletop import Layout

COLOR_NAMES = ('blue', 'green', 'brown', 'orange', 'yellow', 'gray', 'red', 'purple', 'cyan',
               'pink')  # names of shapes.COLORS, in its order
DROP_GAP = 0.001  # objects start this far above what they rest on (VPG does the same)
HEIGHT_TOL = 0.003  # VPG heights within this of a resting half-height are taken as resting
WRITE_Z_ABOVE = 0.002  # the writer gives z only for objects this far above their resting height
VPG_BOX = ((-0.724, -0.276), (-0.224, 0.224), (-0.0001, 0.4))  # VPG's workspace, its robot frame
VPG_TO_OURS_X = 0.5  # x_ours = X_vpg + 0.5; y and z are shared
# VPG's simulator imported these meshes turned by Ry(+90 deg), a quarter turn about the mesh y axis,
# so VPG's Euler angles apply to the turned mesh. With the turn, every line of these shapes in the
# public cases (parked ones too) has the height its angles give, and the cases load without
# interpenetration; without it, arches and prisms lying on a side come out a quarter turn off in
# yaw and overlap their neighbours by 2-4 cm. Tall boxes and octagons fit only unturned; cubes
# cannot tell.
VPG_TURNED = frozenset({'prism', 'arch', 'disk', 'cylinder'})
VPG_IMPORT_TURN = np.rint(euler_xyz_matrix(0.0, math.pi / 2, 0.0))

_OBJECT_FIELDS = ('shape', 'colour', 'x', 'y', 'yaw_deg', 'z')
_OCCLUDER_FIELDS = ('occluder', 'slot', 'x', 'y', 'z', 'yaw_deg')
_VPG_FIELDS = ('mesh', 'red', 'green', 'blue', 'x', 'y', 'z', 'euler_a', 'euler_b', 'euler_c')
_COMMENT = re.compile(r'^\s*#.*|\s#(\s.*)?$')
MAX_FILE_BYTES = 1_000_000  # a case file is a few dozen lines
OCCLUDER_REACH = 1.0  # m: occluders stand within this of the workspace centre, up to this high
OVERLAP_TOLERANCE = 0.003  # m: deeper interpenetration as placed means a broken case
SAME_SPOT = 0.005  # m: two objects whose centres are closer than this are placed at one spot
MAX_CASE_OBJECTS = 128  # objects in one case: each takes an object slot of the compiled scene


class ScenarioError(Error):
  """A case file or case that cannot be loaded; the message names the file and line."""


@dataclasses.dataclass(frozen=True)
class CaseObject:
  shape: str
  color: tuple[float, float, float]
  pos: tuple[float, float, float]  # centre, workspace frame (m)
  quat: tuple[float, float, float, float]  # w, x, y, z
  line: int  # line of the case file it came from


@dataclasses.dataclass(frozen=True)
class CaseOccluder:
  slot: int
  pos: tuple[float, float, float]
  yaw: float  # radians
  line: int


@dataclasses.dataclass(frozen=True)
class Case:
  name: str
  path: str
  objects: tuple[CaseObject, ...]
  occluders: tuple[CaseOccluder, ...] = ()
  parked_lines: tuple[int, ...] = ()  # VPG lines outside VPG's workspace: parked, not in play


MESSAGE_LIMIT = 300  # characters of an error: a field of a damaged file can be megabytes


def _error(path, line: int, field: str, message: str) -> ScenarioError:
  text = f'{path}:{line}: field {field[:40]!r}: {message}'
  return ScenarioError(text if len(text) <= MESSAGE_LIMIT else text[:MESSAGE_LIMIT - 3] + '...')


def _number(path, line: int, field: str, text: str) -> float:
  try:
    value = float(text)
  except ValueError:
    raise _error(path, line, field, f'{text!r} is not a number') from None
  if not math.isfinite(value):
    raise _error(path, line, field, f'{text!r} is not finite')
  return value


def _check_count(path, line: int, fields: list[str], names: tuple[str, ...], optional: int = 0):
  """Raises unless `fields` holds all of `names` but the last `optional` ones."""
  usage = ' '.join(f'<{n}>' if i < len(names) - optional else f'[<{n}>]'
                   for i, n in enumerate(names))
  if len(fields) < len(names) - optional:
    raise _error(path, line, names[len(fields)],
                 f'missing: expected {usage}, got {len(fields)} fields')
  if len(fields) > len(names):
    raise _error(path, line, f'#{len(names) + 1}',
                 f'unexpected {fields[len(names)]!r}: expected {usage}, got {len(fields)} fields')


def _color(path, line: int, text: str) -> tuple[float, float, float]:
  if text in COLOR_NAMES:
    return tuple(float(c) for c in shapes.COLORS[COLOR_NAMES.index(text)])
  if re.fullmatch(r'#[0-9a-fA-F]{6}', text):
    return tuple(int(text[i:i + 2], 16) / 255.0 for i in (1, 3, 5))
  raise _error(path, line, 'colour',
               f'unknown colour {text!r}; use one of {", ".join(COLOR_NAMES)} or #rrggbb')


def _color_text(color) -> str:
  dist = np.max(np.abs(shapes.COLORS - np.asarray(color)), axis=1)
  if dist.min() < 0.5 / 255:
    return COLOR_NAMES[int(dist.argmin())]
  return '#' + ''.join(f'{round(255 * float(c)):02x}' for c in color)


def rest_height(shape: str) -> float:
  """Centre height of `shape` dropped on the table in its rest orientation."""
  return 0.5 * float(shapes.shape(shape).rest_extent[2]) + DROP_GAP


def rest_quat(shape: str, yaw: float) -> tuple[float, ...]:
  """Orientation (w, x, y, z) of `shape` resting on the table, turned by `yaw` (rad)."""
  quat = quat_mul(yaw_quat(jnp.float32(yaw)), jnp.asarray(shapes.shape(shape).rest_quat))
  return tuple(float(q) for q in np.asarray(quat))


# ------------------------------------------------------------------------------ our format
def _yaw(degrees: float) -> float:
  """Radians of any finite angle in degrees, reduced in float64 first (1e300 deg stays exact)."""
  return math.radians(math.fmod(degrees, 360.0))


def _read_scn(path, text: str, workspace_half: float, workspace_top: float):
  objects, occluders, occluder_lines = [], [], {}
  for n, raw in enumerate(text.split('\n'), 1):
    fields = _COMMENT.sub('', raw).split()
    if not fields:
      continue
    if fields[0] == 'occluder':
      _check_count(path, n, fields, _OCCLUDER_FIELDS)
      try:
        slot = int(fields[1])
      except ValueError:
        raise _error(path, n, 'slot', f'{fields[1]!r} is not an integer') from None
      if slot < 0:
        raise _error(path, n, 'slot', f'{slot} is negative')
      if slot in occluder_lines:
        raise _error(path, n, 'slot', f'occluder {slot} is already placed on line '
                     f'{occluder_lines[slot]}')
      occluder_lines[slot] = n
      x, y, z, yaw = (_number(path, n, name, t) for name, t in zip(_OCCLUDER_FIELDS[2:],
                                                                   fields[2:]))
      for name, v in (('x', x), ('y', y)):
        if abs(v) > OCCLUDER_REACH:
          raise _error(path, n, name, f'{v:g}: occluders stand within |{name}| <= '
                       f'{OCCLUDER_REACH:g} m')
      if max(abs(x), abs(y)) <= workspace_half:
        raise _error(path, n, 'x', f'({x:g}, {y:g}) lies inside the workspace (|x|, |y| <= '
                     f'{workspace_half:g}); occluders stand outside it')
      if not 0.0 < z <= OCCLUDER_REACH:
        raise _error(path, n, 'z', f'{z:g}: an occluder\'s centre is above the table, at most '
                     f'{OCCLUDER_REACH:g} m')
      occluders.append(CaseOccluder(slot, (x, y, z), _yaw(yaw), n))
      continue
    _check_count(path, n, fields, _OBJECT_FIELDS, optional=1)
    shape = fields[0]
    if shape not in shapes.SHAPES:
      shape = _mesh_shape(path, n, shape, workspace_half)
    color = _color(path, n, fields[1])
    x, y, yaw = (_number(path, n, name, t) for name, t in zip(('x', 'y', 'yaw_deg'), fields[2:5]))
    for name, v in (('x', x), ('y', y)):
      if abs(v) > workspace_half:
        raise _error(path, n, name, f'{v:g} lies outside the workspace '
                     f'(|{name}| <= {workspace_half:g})')
    z = rest_height(shape)
    if len(fields) == 6:
      z = _number(path, n, 'z', fields[5])
      lowest = 0.5 * float(shapes.shape(shape).rest_extent[2])
      if z < lowest:
        raise _error(path, n, 'z', f'{z:g} puts the {shape} into the table (lowest {lowest:g})')
      if z > workspace_top:
        raise _error(path, n, 'z', f'{z:g} lies above the workspace (z <= {workspace_top:g})')
    objects.append(CaseObject(shape, color, (x, y, z), rest_quat(shape, _yaw(yaw)), n))
  return objects, occluders


def _mesh_shape(path, line: int, text: str, workspace_half: float) -> str:
  """The absolute mesh reference of a `.scn` line's shape field, read and checked here."""
  try:
    reference = shapes.reference(text, pathlib.Path(path).parent)
    extent = shapes.shape(reference).rest_extent
  except meshes.MeshError as e:
    raise _error(path, line, 'shape', str(e)) from None
  if max(extent[:2]) > 2 * workspace_half:
    raise _error(path, line, 'shape', f'{max(extent[:2]):g} m across, wider than the workspace')
  return reference


def write_scenario(case: Case, path) -> None:
  """Writes `case` in our format. Objects must rest in their shape's `rest_quat` turned about z."""
  lines = [f'# {case.name} (from {case.path})', '# shape colour x y yaw_deg [z]']
  for obj in case.objects:
    rest = np.asarray(shapes.shape(obj.shape).rest_quat) * np.array([1.0, -1.0, -1.0, -1.0])
    turn = np.asarray(quat_mul(jnp.asarray(obj.quat), jnp.asarray(rest)))  # quat * rest^-1
    if max(abs(turn[1]), abs(turn[2])) > 1e-3:
      raise ScenarioError(f'{case.path}:{obj.line}: the {obj.shape} is not in its rest '
                          'orientation turned about z, which the .scn format cannot store')
    yaw = math.degrees(2.0 * math.atan2(turn[3], turn[0]))
    yaw = (yaw + 180.0) % 360.0 - 180.0
    x, y, z = obj.pos
    fields = [obj.shape, _color_text(obj.color), f'{x:.5f}', f'{y:.5f}', f'{yaw:.3f}']
    if z > rest_height(obj.shape) + WRITE_Z_ABOVE:
      fields.append(f'{z:.5f}')
    lines.append(' '.join(fields))
  for occ in case.occluders:
    x, y, z = occ.pos
    lines.append(f'occluder {occ.slot} {x:.5f} {y:.5f} {z:.5f} {math.degrees(occ.yaw):.3f}')
  pathlib.Path(path).write_text('\n'.join(lines) + '\n')


# ------------------------------------------------------------------------------ VPG's format
def _vpg_pose(shape: str, euler, z: float):
  """Resting orientation matrix and centre height of a VPG object with Euler angles `euler`.

  Keeps R = Rx(A) Ry(B) Rz(C) (after the import turn, see VPG_TURNED) where it explains the
  height Z, and also where Z is above every face (the object lies on another one: it keeps Z).
  Otherwise the object rests on the axis-aligned face whose half-height matches Z (VPG drops
  1 mm above the table), ties (within 0.5 mm) going to the face R holds most nearly down, and
  keeps the yaw of its long horizontal side from R.
  """
  extent = np.asarray(shapes.shape(shape).extent)
  rot = euler_xyz_matrix(*euler)
  if shape in VPG_TURNED:
    rot = rot @ VPG_IMPORT_TURN
  half = 0.5 * float((np.abs(rot) @ extent)[2])
  if abs(half - z) <= HEIGHT_TOL:
    return rot, half + DROP_GAP
  faces = 0.5 * extent
  if z - DROP_GAP - faces.max() > HEIGHT_TOL:
    return rot, z
  miss = np.abs(faces - (z - DROP_GAP))
  up, sign = max(((a, s) for a in range(3) if miss[a] <= miss.min() + 5e-4 for s in (1, -1)),
                 key=lambda c: round(c[1] * rot[2, c[0]], 1))
  flat = [a for a in range(3) if a != up]
  long_side = max(flat, key=lambda a: extent[a])
  other = flat[0] if flat[1] == long_side else flat[1]
  keep = long_side if np.hypot(*rot[:2, long_side]) >= 0.5 else other
  base = np.zeros((3, 3))  # `up` vertical, `keep` along world x
  base[2, up], base[0, keep] = sign, 1.0
  last = 3 - up - keep
  base[:, last] = np.cross(base[:, (last + 1) % 3], base[:, (last + 2) % 3])
  yaw = math.atan2(rot[1, keep], rot[0, keep])
  return euler_xyz_matrix(0.0, 0.0, yaw) @ base, float(faces[up]) + DROP_GAP


def _read_vpg(path, text: str, blocks: str):
  table = shapes.BLOCK_TABLES[blocks]
  objects, parked = [], []
  for n, raw in enumerate(text.split('\n'), 1):
    fields = raw.split()
    if not fields:
      continue
    _check_count(path, n, fields, _VPG_FIELDS)
    if fields[0] not in table:
      raise _error(path, n, 'mesh', f'unknown mesh {fields[0]!r} in the {blocks!r} block table; '
                   f'known: {", ".join(table)}')
    shape = table[fields[0]]
    values = [_number(path, n, name, t) for name, t in zip(_VPG_FIELDS[1:], fields[1:])]
    color, xyz, euler = values[:3], values[3:6], values[6:]
    for name, c in zip(_VPG_FIELDS[1:4], color):
      if not 0.0 <= c <= 1.0:
        raise _error(path, n, name, f'{c:g} is not in 0..1')
    if not all(lo <= v <= hi for v, (lo, hi) in zip(xyz, VPG_BOX)):
      parked.append(n)  # parked out of play by VPG
      continue
    euler = [math.fmod(a, 2 * math.pi) for a in euler]
    rot, z = _vpg_pose(shape, euler, xyz[2])
    objects.append(CaseObject(shape, tuple(color), (xyz[0] + VPG_TO_OURS_X, xyz[1], z),
                              tuple(float(q) for q in matrix_to_quat(rot)), n))
  return objects, [], parked


def _read_text(path: pathlib.Path) -> str:
  """The UTF-8 text of a regular file; any other file, OS error or bad byte is a ScenarioError."""
  try:
    info = os.stat(path)
  except OSError as e:
    raise ScenarioError(f'{path}: cannot read the case file: {e.strerror}') from None
  if not stat.S_ISREG(info.st_mode):  # a FIFO would block the reader, a folder has no text
    raise ScenarioError(f'{path}: not a regular file')
  if info.st_size > MAX_FILE_BYTES:
    raise ScenarioError(f'{path}: {info.st_size} bytes; a case file holds at most '
                        f'{MAX_FILE_BYTES}')
  try:
    data = path.read_bytes()
  except OSError as e:
    raise ScenarioError(f'{path}: cannot read the case file: {e.strerror}') from None
  try:
    return data.decode('utf-8')
  except UnicodeDecodeError as e:
    line = data[:e.start].count(b'\n') + 1
    raise ScenarioError(f'{path}:{line}: not UTF-8 text (byte {data[e.start]:#04x})') from None


def read_case(path, workspace_half: float = 0.224, workspace_top: float = 0.4,
              blocks: str = 'vpg') -> Case:
  """Loads a case: `.scn` in our format, `.txt` in VPG's.

  `workspace_half` and `workspace_top` bound the objects of `.scn` files; VPG files use VPG's own
  workspace box, and their lines outside it (objects VPG parked) are kept in `parked_lines`.
  `blocks` names the table of `shapes.BLOCK_TABLES` that VPG files' mesh names are read with.
  """
  if blocks not in shapes.BLOCK_TABLES:
    raise ScenarioError(f'unknown block table {blocks!r}; known: '
                        f'{", ".join(shapes.BLOCK_TABLES)}')
  path = pathlib.Path(path)
  if path.suffix not in ('.scn', '.txt'):
    raise ScenarioError(f'{path}: unknown case format {path.suffix!r}; expected .scn (ours) or '
                        '.txt (VPG)')
  text = _read_text(path)
  parked = []
  if path.suffix == '.scn':
    objects, occluders = _read_scn(path, text, workspace_half, workspace_top)
  else:
    objects, occluders, parked = _read_vpg(path, text, blocks)
  if not objects:
    where = (f'; its {len(parked)} lines ({", ".join(map(str, parked[:10]))}) all lie outside '
             'VPG\'s workspace, where VPG parks unused objects') if parked else ''
    raise ScenarioError(f'{path}: the case holds no objects{where}')
  if len(objects) > MAX_CASE_OBJECTS:
    raise ScenarioError(f'{path}: {len(objects)} objects; a case holds at most '
                        f'{MAX_CASE_OBJECTS} (line {objects[MAX_CASE_OBJECTS].line} is the first '
                        'beyond)')
  return Case(path.stem, str(path), tuple(objects), tuple(occluders), tuple(parked))


# ------------------------------------------------------------------------------ layouts
def case_slots(case: Case, env) -> list[int]:
  """The object slot of each of `case`'s objects: the next free slot of its shape."""
  slot_shapes = env.scene.index.slot_shapes
  need, have = collections.Counter(o.shape for o in case.objects), collections.Counter(slot_shapes)
  short = [f'{need[s]} {s!r} slots and the pool has {have[s]}' for s in need if need[s] > have[s]]
  if short:
    raise ScenarioError(f'{case.path}: the case needs {"; ".join(short)}; add them to the '
                        'scene.pool setting')
  free = {s: [i for i, t in enumerate(slot_shapes) if t == s] for s in need}
  return [free[o.shape].pop(0) for o in case.objects]


def case_to_layout(case: Case, env) -> Layout:
  """The starting layout of `case` in `env`, each object in its `case_slots` slot."""
  m = env.num_slots
  in_play = np.zeros(m, bool)
  pos = np.array([park_position(i) for i in range(m)])
  quat = np.tile([1.0, 0.0, 0.0, 0.0], (m, 1))
  color = np.full((m, 3), 0.5)
  for i, obj in zip(case_slots(case, env), case.objects):
    in_play[i], pos[i], quat[i], color[i] = True, obj.pos, obj.quat, obj.color
  occ_pos, occ_quat = (np.array(a) for a in env.parked_occluders())
  for occ in case.occluders:
    if occ.slot >= len(occ_pos):
      raise ScenarioError(f'{case.path}:{occ.line}: field \'slot\': occluder {occ.slot} is out '
                          f'of range: scene.occluders has {len(occ_pos)} slots')
    occ_pos[occ.slot], occ_quat[occ.slot] = occ.pos, np.asarray(yaw_quat(occ.yaw))
  f32 = lambda a: jnp.asarray(a, jnp.float32)
  return Layout(in_play=jnp.asarray(in_play), pos=f32(pos), quat=f32(quat), color=f32(color),
                occluder_pos=f32(occ_pos), occluder_quat=f32(occ_quat))


def overlaps(case: Case, env, tolerance: float = OVERLAP_TOLERANCE) -> list[str]:
  """One message per pair of `case`'s objects that interpenetrate by more than `tolerance` as
  placed, before any settling, naming both lines (native MuJoCo's collision detection; objects
  placed at one spot, which it may find no contact between, by their centres)."""
  m, index = env.scene.mj_model, env.scene.index
  layout = case_to_layout(case, env)
  centres = [np.asarray(o.pos) for o in case.objects]
  stacked = [f'{case.path}:{a.line} and line {b.line}: the objects are placed at one spot '
             f'(centres {1000 * np.linalg.norm(centres[i] - centres[j]):.1f} mm apart)'
             for i, a in enumerate(case.objects) for j, b in enumerate(case.objects)
             if i < j and np.linalg.norm(centres[i] - centres[j]) < SAME_SPOT]
  if stacked:
    return stacked
  data = mujoco.MjData(m)
  for slot, (pos, quat) in enumerate(zip(np.asarray(layout.pos), np.asarray(layout.quat))):
    data.qpos[index.slot_qpos[slot]:index.slot_qpos[slot] + 7] = np.concatenate([pos, quat])
  line_of = {slot: obj.line for slot, obj in zip(case_slots(case, env), case.objects)}
  mujoco.mj_forward(m, data)
  deepest = {}
  n = data.ncon
  for g1, g2, dist in zip(data.contact.geom1[:n], data.contact.geom2[:n], data.contact.dist[:n]):
    a, b = sorted((int(index.geom_slot[g1]), int(index.geom_slot[g2])))
    if a in line_of and b in line_of and a != b and -dist > tolerance:
      deepest[a, b] = max(deepest.get((a, b), 0.0), -float(dist))
  return [f'{case.path}:{line_of[a]} and line {line_of[b]}: the objects interpenetrate by '
          f'{1000 * depth:.1f} mm' for (a, b), depth in sorted(deepest.items())]


# m: the farthest `fit_overlaps` moves an object unless told otherwise. The MV-COBA authors' own
# cases need up to 66 mm (docs/results/other-simulators.md): objects their simulator left resting
# on each other, which our shapes place a few millimetres into one another.
FIT_BOUND = 0.07
MAX_FIT_BOUND = 0.2  # m: a larger move is not fitting a case but rewriting it
_FIT_STEPS = 16  # bisection steps of a move: bound / 2**16, under a micrometre


def _fit_directions(normals) -> list[np.ndarray]:
  """Unit directions a fitted object may move along: up, each contact's normal and their
  depth-weighted sum, each also tilted up by 30 and 60 degrees and laid flat (a leaning object
  that sank into its neighbour clears it soonest at a slant)."""
  up = np.array([0.0, 0.0, 1.0])
  out = [up]
  for n in [*normals, np.sum(normals, axis=0)]:
    flat = np.array([n[0], n[1], 0.0])
    if np.linalg.norm(flat) < 1e-9:
      continue
    flat /= np.linalg.norm(flat)
    out += [flat, *(np.cos(a) * flat + np.sin(a) * up for a in (np.pi / 6, np.pi / 3))]
    if np.linalg.norm(n) > 1e-9:
      out.append(n / np.linalg.norm(n))
  return out


def _contacts(m, data, index, placed: set, slot: int, pos, quat, tolerance: float):
  """(deepest penetration, the contact normals weighted by depth, pointing from the placed
  objects to `slot`) of `slot` at `pos` against the `placed` slots."""
  data.qpos[index.slot_qpos[slot]:index.slot_qpos[slot] + 7] = np.concatenate([pos, quat])
  mujoco.mj_fwdPosition(m, data)
  deepest, normals = 0.0, []
  for c in data.contact[:data.ncon]:
    s1, s2 = int(index.geom_slot[c.geom1]), int(index.geom_slot[c.geom2])
    other = s2 if s1 == slot else s1 if s2 == slot else None
    if other is None or other not in placed or -c.dist <= tolerance:
      continue
    deepest = max(deepest, -float(c.dist))
    normals.append(-float(c.dist) * np.asarray(c.frame[:3]) * (1.0 if s2 == slot else -1.0))
  return deepest, normals


def fit_overlaps(case: Case, env, bound: float = FIT_BOUND,
                 tolerance: float = OVERLAP_TOLERANCE) -> tuple[Case, tuple[float, ...]]:
  """`case` made physically valid the way a simulator that drops objects leaves it: objects
  placed in file order, each moved by the least distance that leaves it interpenetrating
  nothing already placed by more than `tolerance`, up along z (onto what it sank into) or
  sideways (away from what it touches, along the contacts' horizontal normal). Objects placed
  earlier never move. Returns the fitted case and each object's move (m, file order); raises
  ScenarioError naming every line that would have to move more than `bound`.

  Native MuJoCo's collision detection on the scene of `env`, as `overlaps`; settling is left to
  the reset, as for any case.
  """
  m, index = env.scene.mj_model, env.scene.index
  data = mujoco.MjData(m)
  slots = case_slots(case, env)
  for slot in range(env.num_slots):  # every slot parked; objects join one at a time
    data.qpos[index.slot_qpos[slot]:index.slot_qpos[slot] + 7] = np.concatenate(
        [park_position(slot), [1.0, 0.0, 0.0, 0.0]])
  placed, fitted, moves, stuck = set(), [], [], []
  contacts = lambda slot, pos, quat: _contacts(m, data, index, placed, slot, pos, quat,
                                               tolerance)

  def least(slot, pos, quat, direction):
    """The shortest move along `direction` (unit) that clears `slot`, or None within `bound`."""
    if contacts(slot, pos + bound * direction, quat)[0] > tolerance:
      return None
    lo, hi = 0.0, bound
    for _ in range(_FIT_STEPS):
      mid = 0.5 * (lo + hi)
      if contacts(slot, pos + mid * direction, quat)[0] > tolerance:
        lo = mid
      else:
        hi = mid
    return hi

  for slot, obj in zip(slots, case.objects):
    pos, quat = np.asarray(obj.pos, float), np.asarray(obj.quat, float)
    deepest, normals = contacts(slot, pos, quat)
    move = np.zeros(3)
    if deepest > tolerance:
      moves_tried = [(d, u) for u in _fit_directions(normals)
                     if (d := least(slot, pos, quat, u)) is not None]
      if moves_tried:
        d, u = min(moves_tried, key=lambda t: t[0])
        move = d * u
      else:
        stuck.append(obj)
      contacts(slot, pos + move, quat)
    placed.add(slot)
    fitted.append(dataclasses.replace(obj, pos=tuple(float(v) for v in pos + move)))
    moves.append(float(np.linalg.norm(move)))
  if stuck:
    raise ScenarioError('\n'.join(
        f'{case.path}:{obj.line}: the {obj.shape} would move more than {1000 * bound:.0f} mm to '
        'clear the objects listed before it (raise the bound of --fit-overlaps)' for obj in stuck))
  return dataclasses.replace(case, objects=tuple(fitted)), tuple(moves)


def stack_layouts(layouts) -> Layout:
  """One batched Layout (leading axis = case) for vmapped resets."""
  return jax.tree.map(lambda *xs: jnp.stack(xs), *layouts)


def half_height(shape: str, quat) -> float:
  """Half the vertical size of `shape`'s bounding box in orientation `quat` (w, x, y, z)."""
  rot = np.zeros(9)
  mujoco.mju_quat2Mat(rot, np.asarray(quat, float))
  return 0.5 * float((np.abs(rot.reshape(3, 3)) @ np.asarray(shapes.shape(shape).extent))[2])
