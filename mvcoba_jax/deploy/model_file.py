"""model.json, the contract between an export and a runtime: every field an action depends on,
read once, typed and checked when an export is opened, so a damaged or hand-edited file is
refused with one line naming the field instead of acting wrongly later. Pure Python (the deploy
path reads it without JAX); `export.describe` writes it, `policy.load_exported` and
`deploy.OnnxPolicy` open it through `read`.
"""
from __future__ import annotations

import dataclasses
import json
import math
import pathlib

from mvcoba_jax.deploy.calibration import DeployError

FORMAT = 'mvcoba-jax-export/2'  # what export writes: the graph outputs the action
# Format 1's graph stopped at the maps and left the rule to the runtime: its parameters still
# load (`policy.load`), its graph is refused by `deploy.OnnxPolicy`.
FORMATS = (FORMAT, 'mvcoba-jax-export/1')


@dataclasses.dataclass(frozen=True)
class ModelFile:
  """What acting on an export needs from its model.json, checked."""
  raw: dict  # the whole file, for what no action depends on (figures, source, names)
  graph_decides: bool  # the ONNX graph outputs the action (format 2)
  push: int
  grasp: int
  angles_rad: tuple[float, ...]
  resolution_m: float
  grid_size: int
  workspace_half_m: float
  num_views: int
  views_used: tuple[int, ...]
  onnx_file: pathlib.Path  # inside the folder; absent from a shipped policy without its graph
  change_min: float
  change_max: float
  change_area: float
  failed_grasp_changes: bool  # False: a grasp that held nothing is no change (absent: True)
  fill_unseen: bool  # each view's unseen cells filled from the others first (absent: False)


def read(folder) -> ModelFile:
  """The checked model.json of an export folder; DeployError naming the file, the field and the
  problem, for the first field that is missing, mistyped or out of range, an unknown format,
  or an ONNX file outside the folder."""
  folder = pathlib.Path(folder)
  path = folder / 'model.json'
  try:
    raw = json.loads(path.read_text(), parse_constant=_no_constant)
  except (OSError, ValueError, RecursionError) as e:
    raise DeployError(f'{path}: not an export ({type(e).__name__}: {str(e)[:120]})') from None
  field = _Fields(raw, path)
  fmt = field.get('format', str)
  if fmt not in FORMATS:
    raise DeployError(f'{path}: format {fmt!r}: this runtime reads {", ".join(FORMATS)} '
                      '(another version of mvcoba_jax wrote it)')
  push = field.get('primitives.push', int, (0, 1))
  grasp = field.get('primitives.grasp', int, (0, 1))
  if push == grasp:
    raise DeployError(f'{path}: primitives.push and primitives.grasp are both {push}')
  k = field.get('rotations.num_rotations', int, (1, 64))
  angles = field.get('rotations.angles_rad', list)
  if len(angles) != k or not all(_real(a) for a in angles):
    raise DeployError(f'{path}: rotations.angles_rad: {k} finite numbers expected')
  res = field.get('heightmap.resolution_m', float, (1e-4, 0.05))
  half = field.get('heightmap.workspace_half_m', float, (0.01, 2.0))
  side = field.get('heightmap.grid_size', int, (1, 4096))
  if side != round(2 * half / res):
    raise DeployError(f'{path}: heightmap.grid_size {side} is not 2 x '
                      f'heightmap.workspace_half_m / heightmap.resolution_m = {2 * half / res:g}')
  views = field.get('heightmap.num_views', int, (1, 16))
  used = field.get('heightmap.views_used', list)
  if not used or not all(type(v) is int and 0 <= v < views for v in used) or len(
      set(used)) != len(used):
    raise DeployError(f'{path}: heightmap.views_used {str(used)[:60]}: distinct view indices '
                      f'below heightmap.num_views ({views}) expected')
  onnx_name = field.get('onnx.file', str)
  onnx_file = (folder / onnx_name).resolve()
  if onnx_file.parent != folder.resolve():
    raise DeployError(f'{path}: onnx.file {onnx_name!r} lies outside the export\'s folder')
  change = {name: field.get(f'config.perception.{name}', float, (0.0, 1.0))
            for name in ('change_min', 'change_max', 'change_area')}
  if abs(field.get('config.perception.heightmap_resolution', float, (1e-4, 0.05)) - res) > 1e-12:
    raise DeployError(f'{path}: config.perception.heightmap_resolution is not '
                      'heightmap.resolution_m')
  perception = raw['config']['perception']
  flags = {name: perception.get(name, default) for name, default in
           (('failed_grasp_changes', True), ('fill_unseen', False))}
  for name, value in flags.items():
    if type(value) is not bool:
      raise DeployError(f'{path}: config.perception.{name} {str(value)[:40]!r}: true or false '
                        'expected')
  return ModelFile(raw=raw, graph_decides=fmt == FORMAT, push=push, grasp=grasp, **flags,
                   angles_rad=tuple(float(a) for a in angles), resolution_m=res, grid_size=side,
                   workspace_half_m=half, num_views=views, views_used=tuple(used),
                   onnx_file=onnx_file, **change)


class _Fields:
  """Dotted fields of a JSON object, each checked for its type and range as it is read."""

  def __init__(self, raw, path: pathlib.Path):
    self.raw, self.path = raw, path

  def get(self, dotted: str, kind: type, bounds: tuple | None = None):
    value = self.raw
    for key in dotted.split('.'):
      if not isinstance(value, dict) or key not in value:
        raise DeployError(f'{self.path}: {dotted} is missing')
      value = value[key]
    if kind is float and _real(value):
      value = float(value)
    elif type(value) is not kind:  # bool is not int here
      raise DeployError(f'{self.path}: {dotted} {str(value)[:40]!r}: a {kind.__name__} expected')
    if bounds and not bounds[0] <= value <= bounds[1]:
      raise DeployError(f'{self.path}: {dotted} {value!r} outside {bounds[0]:g}..{bounds[1]:g}')
    return value


def _real(value) -> bool:
  return type(value) in (int, float) and math.isfinite(value)


def _no_constant(name: str):
  raise ValueError(f'{name} is not a number JSON allows')
