"""What may reach a trained network and what may leave it for a robot, checked the same way by the
JAX policy (`policy.Policy.act`) and the exported one (`deploy.OnnxPolicy.act`); numpy only.

Before the network, an observation (colour (V, R, R, 3), depth (V, R, R)) must have the policy's
views and grid, real numbers, heights in metres within [-5 mm, top] (a height above `top` is
refused as a wrong unit: depth in millimetres reads 30 m) and colour scaled by its dtype (uint8
/ 255, uint16 / 65535, floats already in 0..1, else refused). A non-finite height or colour is a
cell the camera did not see: 0, as a missing point is, never fed on; a view with no finite value
is a camera that returned nothing, refused. After the network, the
action must have a finite score, a finite angle and a position inside the workspace on or above
the table. Each check names the first problem in one line, or passes.
"""
from __future__ import annotations

import math

import numpy as np

from mvcoba_jax.sim.contract import BELOW_TABLE  # heights lower are not the table's

COLOR_SCALES = {np.dtype(np.uint8): 255.0, np.dtype(np.uint16): 65535.0}


class Refused(ValueError):
  """An input or an action that must not reach the network or the robot; says why in one line."""


def observation(color, depth, views: int, side: int, top: float
                ) -> tuple[np.ndarray, np.ndarray]:
  """(colour float32 0..1, depth float32 m) of one observation as the network may take it, its
  non-finite cells 0; raises Refused naming the first problem."""
  depth = _numbers(depth, 'depth')
  color = _numbers(color, 'colour')
  if depth.shape != (views, side, side):
    raise Refused(f'depth of shape {depth.shape}: the policy takes ({views}, {side}, {side}) '
                  '(views, rows, cols)')
  if color.shape != (views, side, side, 3):
    raise Refused(f'colour of shape {color.shape}: the policy takes ({views}, {side}, {side}, 3) '
                  '(views, rows, cols, RGB)')
  for name, values in (('depth', depth), ('colour', color)):
    blind = [v for v in range(views) if not np.isfinite(values[v]).any()]
    if blind:
      raise Refused(f'view {blind[0]}: its {name} holds no finite value (a camera that returned '
                    'nothing)')
  scale = COLOR_SCALES.get(color.dtype)
  if scale is None and color.dtype.kind not in 'f':
    raise Refused(f'colour of dtype {color.dtype}: uint8, uint16 or floats in 0..1')
  color = np.asarray(color, np.float64) / (scale or 1.0)
  color = np.where(np.isfinite(color), color, 0.0)
  if color.min(initial=0.0) < 0.0 or color.max(initial=0.0) > 1.0:
    raise Refused(f'colour values from {color.min():g} to {color.max():g}: floats must lie in '
                  '0..1 (or pass uint8 0..255)')
  depth = np.where(np.isfinite(depth), np.asarray(depth, np.float64), 0.0)
  low, high = depth.min(initial=0.0), depth.max(initial=0.0)
  if high > top:
    raise Refused(f'depth up to {high:g}: heights above the table in metres, at most the '
                  f'workspace top {top:g} m (millimetres?)')
  if low < BELOW_TABLE:
    raise Refused(f'depth down to {low:g} m: heights above the table cannot lie more than '
                  f'{-BELOW_TABLE * 1000:g} mm below it')
  return color.astype(np.float32), np.clip(depth, 0.0, None).astype(np.float32)


def seen(values, depth: np.ndarray) -> np.ndarray:
  """The observation's seen mask (V, R, R) as booleans of the depth's shape; raises Refused
  naming what is wrong (missing, another shape, not booleans)."""
  if values is None:
    raise Refused('seen is needed: this policy fills each view\'s unseen cells from the others')
  mask = np.asarray(values)
  if mask.shape != depth.shape or mask.dtype != np.bool_:
    raise Refused(f'seen of shape {mask.shape} and dtype {mask.dtype}: booleans of the depth\'s '
                  f'shape {depth.shape}')
  return mask


def sighted(mask: np.ndarray, views, names=None) -> None:
  """Raises Refused when a view the network reads (`views`, named by `names` where given) saw
  none of the workspace: its heightmap is no observation of the scene."""
  blind = [str(v if names is None else names[v]) for v in views if not mask[v].any()]
  if blind:
    raise Refused(f'{"camera" if names else "view"} {", ".join(blind)} sees none of the '
                  'workspace')


def action(q: float, angle: float, position: tuple[float, float, float], half: float,
           top: float) -> None:
  """Raises Refused unless the action has a finite score and angle and its workspace position
  (x, y, z) lies within +-half and on or above the table, up to top."""
  if not math.isfinite(q):
    raise Refused(f'the network scored the action {q} (non-finite): no action is taken')
  if not math.isfinite(angle):
    raise Refused(f'the action\'s angle is {angle} (non-finite)')
  x, y, z = position
  if not all(math.isfinite(v) for v in position) or not (
      abs(x) <= half and abs(y) <= half and 0.0 <= z <= top):
    raise Refused(f'the action at ({x:.3f}, {y:.3f}, {z:.3f}) m leaves the workspace (+-{half:g} '
                  f'm, 0 to {top:g} m)')


def _numbers(values, name: str) -> np.ndarray:
  try:
    array = np.asarray(values)
  except (ValueError, TypeError) as e:  # ragged lists
    raise Refused(f'{name}: not an array of numbers ({str(e)[:80]})') from None
  if array.dtype.kind not in 'uif':
    raise Refused(f'{name} of dtype {array.dtype}: numbers expected')
  return array
