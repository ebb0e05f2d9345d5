"""A lab's calibration: each camera's pinhole intrinsics, its pose in the robot's base frame and
its depth scale, and where the training workspace lies in the base frame. One JSON file,
checked field by field (`load_calibration`); every problem is one line naming the file and the
field.

    {"workspace": {"center": [0.5, 0.0, 0.02], "yaw_deg": 0.0,
                   "half": 0.224, "top": 0.4, "resolution": 0.004},
     "cameras": [{"name": "left", "width": 640, "height": 480,
                  "fx": 615.0, "fy": 615.0, "cx": 319.5, "cy": 239.5,
                  "camera_to_base": [[...4 rows of 4...]], "depth_scale": 0.001}]}

Cameras use OpenCV's convention: x right, y down, looking along +z; pixel (u, v) (column, row)
looks along ((u - cx) / fx, (v - cy) / fy, 1), and a depth image holds the distance along +z
(`depth_scale` metres per unit: 0.001 for 16-bit millimetres). `K` (a 3x3 matrix) may stand for
fx, fy, cx, cy. The workspace frame (the one the policy trained in) has its origin at `center`
(metres, base frame: the middle of the workspace on the table's surface), its x axis turned by
`yaw_deg` about the base's z axis, z up; `half`, `top` and `resolution` must be the trained
policy's (its model.json's heightmap).
"""
from __future__ import annotations

import dataclasses
import json
import math
import pathlib

import numpy as np


class DeployError(ValueError):
  """A calibration, image or action that cannot be used, said in one line naming it."""


@dataclasses.dataclass(frozen=True)
class Camera:
  name: str
  width: int
  height: int
  fx: float
  fy: float
  cx: float
  cy: float
  camera_to_base: np.ndarray  # (4, 4)
  depth_scale: float  # metres per unit of the depth image


@dataclasses.dataclass(frozen=True)
class Calibration:
  cameras: tuple[Camera, ...]
  center: np.ndarray  # (3,) workspace origin in the base frame, on the table
  yaw: float  # rad
  half: float
  top: float
  resolution: float

  @property
  def grid(self) -> int:
    return int(round(2 * self.half / self.resolution))

  def base_to_workspace(self) -> np.ndarray:
    """(4, 4) transform of base-frame points to the workspace frame."""
    c, s = math.cos(self.yaw), math.sin(self.yaw)
    out = np.eye(4)
    out[:3, :3] = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    out[:3, 3] = -out[:3, :3] @ self.center
    return out

  def workspace_to_base(self, point) -> np.ndarray:
    """A workspace-frame point (x, y, z) in the base frame."""
    return (np.linalg.inv(self.base_to_workspace()) @ np.append(np.asarray(point, float), 1.0))[:3]


def _number(where: str, value, low: float = -math.inf, high: float = math.inf,
            open_low: bool = False) -> float:
  if (isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value)
      or value < low or value > high or (open_low and value == low)):
    span = f'{"(" if open_low else "["}{low:g}, {high:g}]'
    raise DeployError(f'{where}: {str(value)[:40]!r}: expected a number in {span}')
  return float(value)


def _matrix(where: str, value, shape) -> np.ndarray:
  try:
    array = np.asarray(value)  # as JSON gave it: strings stay strings, and are refused
  except (TypeError, ValueError):
    array = None
  if array is None or array.dtype.kind not in 'if' or array.shape != shape or not np.isfinite(
      array).all():
    raise DeployError(f'{where}: expected a {shape[0]}x{shape[1]} matrix of numbers')
  return array.astype(float)


def _camera(where: str, data) -> Camera:
  if not isinstance(data, dict):
    raise DeployError(f'{where}: expected an object')
  known = {'name', 'width', 'height', 'fx', 'fy', 'cx', 'cy', 'K', 'camera_to_base',
           'depth_scale'}
  unknown = sorted(set(data) - known)
  if unknown:
    raise DeployError(f'{where}: unknown field {unknown[0]!r} (known: {", ".join(sorted(known))})')
  for key in ('width', 'height', 'camera_to_base', 'depth_scale'):
    if key not in data:
      raise DeployError(f'{where}.{key}: missing')
  size = {}
  for key in ('width', 'height'):
    value = data[key]
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 100_000:
      raise DeployError(f'{where}.{key}: {str(value)[:40]!r}: expected pixels in [1, 100000]')
    size[key] = value
  if 'K' in data:
    if any(k in data for k in ('fx', 'fy', 'cx', 'cy')):
      raise DeployError(f'{where}: give K or fx, fy, cx, cy, not both')
    k = _matrix(f'{where}.K', data['K'], (3, 3))
    if k[0, 1] or k[1, 0] or k[2, 0] or k[2, 1] or k[2, 2] != 1:
      raise DeployError(f'{where}.K: expected [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]')
    fx, fy, cx, cy = k[0, 0], k[1, 1], k[0, 2], k[1, 2]
  else:
    missing = [key for key in ('fx', 'fy', 'cx', 'cy') if key not in data]
    if missing:
      raise DeployError(f'{where}.{missing[0]}: missing (or give K)')
    fx, fy, cx, cy = (data[key] for key in ('fx', 'fy', 'cx', 'cy'))
  fx, fy = (_number(f'{where}.{n}', v, 0, 1e6, open_low=True) for n, v in (('fx', fx), ('fy', fy)))
  cx = _number(f'{where}.cx', cx, -1e6, 1e6)
  cy = _number(f'{where}.cy', cy, -1e6, 1e6)
  pose = _matrix(f'{where}.camera_to_base', data['camera_to_base'], (4, 4))
  rotation = pose[:3, :3]
  if (not np.allclose(pose[3], [0, 0, 0, 1]) or not np.allclose(rotation @ rotation.T, np.eye(3),
                                                                  atol=1e-4)
      or np.linalg.det(rotation) < 0):
    raise DeployError(f'{where}.camera_to_base: not a rigid transform (a rotation and a '
                      'translation, last row 0 0 0 1)')
  scale = _number(f'{where}.depth_scale', data['depth_scale'], 0, 10, open_low=True)
  name = data.get('name', where)
  if not isinstance(name, str):
    raise DeployError(f'{where}.name: expected a string')
  return Camera(name=name, width=size['width'], height=size['height'], fx=fx, fy=fy, cx=cx,
                cy=cy, camera_to_base=pose, depth_scale=scale)


def calibration_from_dict(data, where: str = 'calibration') -> Calibration:
  """A Calibration of the JSON object `data` (the module's layout), checked field by field."""
  if not isinstance(data, dict) or set(data) != {'workspace', 'cameras'}:
    raise DeployError(f'{where}: expected an object with "workspace" and "cameras"')
  space = data['workspace']
  if not isinstance(space, dict):
    raise DeployError(f'{where}.workspace: expected an object')
  known = {'center', 'yaw_deg', 'half', 'top', 'resolution'}
  if set(space) - known or 'center' not in space:
    raise DeployError(f'{where}.workspace: fields {", ".join(sorted(known))} ("center" needed)')
  center = _matrix(f'{where}.workspace.center', [space['center']], (1, 3))[0]
  half = _number(f'{where}.workspace.half', space.get('half', 0.224), 0.01, 10)
  top = _number(f'{where}.workspace.top', space.get('top', 0.4), 0.01, 10)
  resolution = _number(f'{where}.workspace.resolution', space.get('resolution', 0.004), 1e-4, 1)
  cells = 2 * half / resolution
  if abs(cells - round(cells)) > 1e-6 * cells:
    raise DeployError(f'{where}.workspace.resolution: {resolution:g} does not tile the '
                      f'{2 * half:g} m workspace')
  yaw = math.radians(_number(f'{where}.workspace.yaw_deg', space.get('yaw_deg', 0.0), -360, 360))
  cameras = data['cameras']
  if not isinstance(cameras, list) or not cameras:
    raise DeployError(f'{where}.cameras: expected a list of at least one camera')
  return Calibration(cameras=tuple(_camera(f'{where}.cameras[{i}]', c)
                                   for i, c in enumerate(cameras)),
                     center=center, yaw=yaw, half=half, top=top, resolution=resolution)


def load_calibration(path) -> Calibration:
  """The Calibration of a JSON file; DeployError names the file and the field on any problem."""
  path = pathlib.Path(path)
  try:
    data = json.loads(path.read_text())
  except (OSError, ValueError, RecursionError) as e:
    raise DeployError(f'{path}: cannot read a calibration ({type(e).__name__}: '
                      f'{str(e)[:120]})') from None
  return calibration_from_dict(data, str(path))
