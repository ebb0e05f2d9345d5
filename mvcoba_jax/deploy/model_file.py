"""model.json, the contract between an export and a runtime: every field an action depends on,
read once, typed and checked when an export is opened, so a damaged or hand-edited file is
refused with one line naming the field instead of acting wrongly later. Pure Python (the deploy
path reads it without JAX); `export.describe` writes it (`as_json`), `policy.load_exported` and
`deploy.OnnxPolicy` open it through `read`.
"""
from __future__ import annotations

import dataclasses
import json
import math
import pathlib

from mvcoba_jax.deploy.calibration import DeployError
from mvcoba_jax.sim.contract import BELOW_TABLE, HEIGHT_UNIT
from mvcoba_jax.sim.contract import GRASP, PUSH, RANGES

FORMAT = 'mvcoba-jax-export/2'  # what export writes: the graph outputs the action
# Format 1's graph stopped at the maps and left the rule to the runtime: its parameters still
# load (`policy.load`), its graph is refused by `deploy.OnnxPolicy`.
FORMATS = (FORMAT, 'mvcoba-jax-export/1')


@dataclasses.dataclass(frozen=True)
class ModelFile:
  """What acting on an export needs from its model.json, checked."""
  graph_decides: bool  # the ONNX graph outputs the action (format 2)
  push: int
  grasp: int
  num_rotations: int
  angles_rad: tuple[float, ...]
  resolution_m: float
  grid_size: int
  workspace_half_m: float
  num_views: int
  views_used: tuple[int, ...]
  height_unit_m: float  # heights are kept in steps of this (the heightmaps' unit)
  below_table_m: float  # points lower than this are not the table's
  onnx_file: str  # the graph's file name, inside the export's folder
  change_min: float
  change_max: float
  change_area: float
  failed_grasp_changes: bool  # False: a grasp that held nothing is no change ...
  failed_grasp_retries: int  # ... past this many such grasps in a row
  fill_unseen: bool  # each view's unseen cells filled from the others first
  push_length_m: float  # how far a push slides along its angle, as in training
  gripper: dict  # the gripper it trained with (config.scene.gripper): name, fingers, opening
  method: str  # the network's method (`methods.names()`)
  checkpoint_step: int  # the training actions behind the parameters
  config: dict  # the whole training config as saved (`config.from_dict` builds it)


# Where model.json holds each field of `ModelFile`, its JSON type and range, and the value a file
# written before the field existed means: `read` and `as_json` both go through this one table.
FIELDS = {
    'config': ('config', dict, None),  # first: the config.* fields below are set inside it
    'push': ('primitives.push', int, (0, 1)),
    'grasp': ('primitives.grasp', int, (0, 1)),
    'num_rotations': ('rotations.num_rotations', int, RANGES['env.num_rotations']),
    'angles_rad': ('rotations.angles_rad', list, None),
    'resolution_m': ('heightmap.resolution_m', float, RANGES['perception.heightmap_resolution']),
    'workspace_half_m': ('heightmap.workspace_half_m', float, RANGES['scene.workspace_half']),
    'grid_size': ('heightmap.grid_size', int, (1, 4096)),
    'num_views': ('heightmap.num_views', int, (1, 16)),
    'views_used': ('heightmap.views_used', list, None),
    'height_unit_m': ('heightmap.height_unit_m', float, (1e-7, 1e-2)),
    'below_table_m': ('heightmap.below_table_m', float, (-0.1, 0.0)),
    'onnx_file': ('onnx.file', str, None),
    'change_min': ('config.perception.change_min', float, RANGES['perception.change_min']),
    'change_max': ('config.perception.change_max', float, RANGES['perception.change_max']),
    'change_area': ('config.perception.change_area', float, RANGES['perception.change_area']),
    'failed_grasp_changes': ('config.perception.failed_grasp_changes', bool, None),
    'failed_grasp_retries': ('config.perception.failed_grasp_retries', int,
                             RANGES['perception.failed_grasp_retries']),
    'fill_unseen': ('config.perception.fill_unseen', bool, None),
    'push_length_m': ('config.env.push_length', float, RANGES['env.push_length']),
    'gripper': ('config.scene.gripper', dict, None),
    'method': ('method', str, None),
    'checkpoint_step': ('source.checkpoint_step', int, (0, 10 ** 12)),  # more than any training
}
# The RG2-like gripper of every export written before the gripper was a config of its own
# (`sim.config.GripperConfig`'s defaults; tests/unit/test_policy_files.py holds them equal).
RG2 = {'name': 'rg2', 'finger_width': 0.02, 'finger_thickness': 0.01, 'finger_length': 0.06,
       'max_opening': 0.11, 'palm': [0.03, 0.15, 0.02], 'finger_force': 15.0,
       'finger_friction': 1.5}
ABSENT = {'height_unit_m': HEIGHT_UNIT, 'below_table_m': BELOW_TABLE,
          'failed_grasp_changes': True, 'failed_grasp_retries': 0, 'fill_unseen': False,
          'gripper': RG2}
_REQUIRED = object()  # a field without a value in ABSENT


def as_json(spec: ModelFile) -> dict:
  """`spec`'s fields as model.json nests them (`FIELDS`): what `export.describe` writes."""
  out = {'format': FORMAT if spec.graph_decides else FORMATS[1]}
  for name, (dotted, _, _) in FIELDS.items():
    *parents, key = dotted.split('.')
    section = out
    for part in parents:
      section = section.setdefault(part, {})
    value = getattr(spec, name)  # tuples as lists, dicts copied: later fields are set inside them
    section[key] = json.loads(json.dumps(value)) if isinstance(value, (tuple, dict)) else value
  return out


def read(folder) -> ModelFile:
  """The checked model.json of an export folder; DeployError naming the file, the field and the
  problem, for the first field that is missing, mistyped or out of range, an unknown format,
  a heightmap unit or floor this runtime does not make, or an ONNX file outside the folder."""
  path = pathlib.Path(folder) / 'model.json'
  try:
    raw = json.loads(path.read_text(), parse_constant=_no_constant)
  except (OSError, ValueError, RecursionError) as e:
    raise DeployError(f'{path}: not an export ({type(e).__name__}: {str(e)[:120]})') from None
  return checked(raw, path)


def checked(raw, path: pathlib.Path) -> ModelFile:
  """`read`'s checks of model.json's content `raw`, as if read from `path` (errors name it):
  what the export runs on what it is about to write."""
  folder = path.parent
  field = _Fields(raw, path)
  fmt = field.get('format', str)
  if fmt not in FORMATS:
    raise DeployError(f'{path}: format {fmt!r}: this runtime reads {", ".join(FORMATS)} '
                      '(another version of mvcoba_jax wrote it)')
  got = {name: field.get(dotted, kind, bounds, ABSENT.get(name, _REQUIRED))
         for name, (dotted, kind, bounds) in FIELDS.items()}
  if (got['push'], got['grasp']) != (PUSH, GRASP):
    raise DeployError(f'{path}: primitives push {got["push"]}, grasp {got["grasp"]}: the graph\'s '
                      f'action numbers push {PUSH} and grasp {GRASP} (its maps\' order)')
  angles = got['angles_rad']
  if len(angles) != got['num_rotations'] or not all(_real(a) for a in angles):
    raise DeployError(f'{path}: rotations.angles_rad: {got["num_rotations"]} finite numbers '
                      'expected')
  res, half, side = got['resolution_m'], got['workspace_half_m'], got['grid_size']
  if side != round(2 * half / res):
    raise DeployError(f'{path}: heightmap.grid_size {side} is not 2 x '
                      f'heightmap.workspace_half_m / heightmap.resolution_m = {2 * half / res:g}')
  views, used = got['num_views'], got['views_used']
  if not used or not all(type(v) is int and 0 <= v < views for v in used) or len(
      set(used)) != len(used):
    raise DeployError(f'{path}: heightmap.views_used {str(used)[:60]}: distinct view indices '
                      f'below heightmap.num_views ({views}) expected')
  for name, own in (('height_unit_m', HEIGHT_UNIT), ('below_table_m', BELOW_TABLE)):
    if abs(got[name] - own) > 1e-12:
      raise DeployError(f'{path}: {FIELDS[name][0]} {got[name]!r}: this runtime\'s heightmaps '
                        f'use {own!r} (another version of mvcoba_jax wrote it)')
  gripper = got['gripper']
  low, high = RANGES['scene.gripper.max_opening']
  if not isinstance(gripper.get('name'), str) or not (
      _real(gripper.get('max_opening')) and low <= gripper['max_opening'] <= high):
    raise DeployError(f'{path}: config.scene.gripper: a name and a max_opening in {low:g}-'
                      f'{high:g} m expected')
  if (folder / got['onnx_file']).resolve().parent != folder.resolve():
    raise DeployError(f'{path}: onnx.file {got["onnx_file"]!r} lies outside the export\'s folder')
  if abs(field.get('config.perception.heightmap_resolution', float,
                   RANGES['perception.heightmap_resolution']) - res) > 1e-12:
    raise DeployError(f'{path}: config.perception.heightmap_resolution is not '
                      'heightmap.resolution_m')
  spec = ModelFile(**{**got, 'angles_rad': tuple(float(a) for a in angles),
                      'views_used': tuple(used)}, graph_decides=fmt == FORMAT)
  return acting_rule(spec, where=f'{path}: config.perception')


def acting_rule(spec: ModelFile, failed_grasp_changes: bool | None = None,
                failed_grasp_retries: int | None = None, where: str = 'acting rule') -> ModelFile:
  """`spec` acting under another change rule after a failed grasp (None keeps model.json's):
  the rule's choice of the next primitive, which the network does not read, as
  `mvcoba-eval --set perception.failed_grasp_retries=N` evaluates it. DeployError when the
  retries are not a whole number in 0-100 or are set with `failed_grasp_changes` on."""
  changes = spec.failed_grasp_changes if failed_grasp_changes is None else failed_grasp_changes
  retries = spec.failed_grasp_retries if failed_grasp_retries is None else failed_grasp_retries
  if type(changes) is not bool:
    raise DeployError(f'{where}: failed_grasp_changes {changes!r}: true or false expected')
  low, high = FIELDS['failed_grasp_retries'][2]
  if type(retries) is not int or not low <= retries <= high:
    raise DeployError(f'{where}: failed_grasp_retries {retries!r}: a whole number in '
                      f'{low}-{high} expected')
  if retries and changes:
    raise DeployError(f'{where}: failed_grasp_retries {retries} needs failed_grasp_changes false '
                      '(with it true a failed grasp that moved the scene is change anyway)')
  return dataclasses.replace(spec, failed_grasp_changes=changes, failed_grasp_retries=retries)


KINDS = {int: 'a whole number', float: 'a number', str: 'a string', bool: 'true or false',
         list: 'a list', dict: 'an object'}  # as a JSON reader names them


class _Fields:
  """Dotted fields of a JSON object, each checked for its type and range as it is read."""

  def __init__(self, raw, path: pathlib.Path):
    self.raw, self.path = raw, path

  def get(self, dotted: str, kind: type, bounds: tuple | None = None, absent=_REQUIRED):
    """The field's value; `absent`, where given, for a field the file does not hold."""
    value = self.raw
    for key in dotted.split('.'):
      if not isinstance(value, dict) or key not in value:
        if absent is not _REQUIRED:
          return absent
        raise DeployError(f'{self.path}: {dotted} is missing')
      value = value[key]
    if kind is float and _real(value):
      value = float(value)
    elif type(value) is not kind:  # bool is not int here
      raise DeployError(f'{self.path}: {dotted} {str(value)[:40]!r}: {KINDS[kind]} expected')
    if bounds and not bounds[0] <= value <= bounds[1]:
      raise DeployError(f'{self.path}: {dotted} {value!r} outside {bounds[0]:g}..{bounds[1]:g}')
    return value


def _real(value) -> bool:
  return type(value) in (int, float) and math.isfinite(value)


def _no_constant(name: str):
  raise ValueError(f'{name} is not a number JSON allows')
