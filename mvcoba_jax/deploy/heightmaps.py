"""Depth (and colour) images of calibrated cameras to the heightmaps a trained policy acts on,
built as training builds them (`mvcoba_jax/perception.py`): each view's points in the workspace
frame, binned into the workspace grid as the contract bins them (`sim.contract.binned`), the
highest point of a cell kept, a cell no point reaches left at 0 and unseen. Missing depth (0, NaN
or infinite) gives no point."""
from __future__ import annotations

import cv2
import numpy as np

from mvcoba_jax.deploy.calibration import Calibration, Camera, DeployError
from mvcoba_jax.sim.contract import HEIGHT_UNIT, binned


def read_depth(path, camera: Camera) -> np.ndarray:
  """A depth image file (16-bit PNG or any format OpenCV reads unchanged) in metres, checked
  against the camera's size."""
  image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
  if image is None:
    raise DeployError(f'{path}: cannot read a depth image')
  if image.ndim != 2:
    raise DeployError(f'{path}: a depth image has one channel, this one {image.shape[2]}')
  return image.astype(np.float64) * camera.depth_scale


def read_color(path) -> np.ndarray:
  """A colour image file (any format OpenCV reads, 8 bits a channel, BGR or BGRA) as RGB uint8;
  a one-channel or 16-bit file (a depth image given as colour) is refused."""
  image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
  if image is None:
    raise DeployError(f'{path}: cannot read a colour image')
  if image.ndim != 3 or image.shape[2] not in (3, 4) or image.dtype != np.uint8:
    channels = 1 if image.ndim == 2 else image.shape[2]
    raise DeployError(f'{path}: a colour image has 3 channels of 8 bits, this one {channels} of '
                      f'{8 * image.dtype.itemsize} (a depth image?)')
  return cv2.cvtColor(image, cv2.COLOR_BGRA2RGB if image.shape[2] == 4 else cv2.COLOR_BGR2RGB)


def _array(value, kinds: str, where: str, what: str) -> np.ndarray:
  """`value` as an array whose dtype is of `kinds` (numpy's kind letters), else DeployError."""
  try:
    array = np.asarray(value)
  except (ValueError, TypeError) as e:
    raise DeployError(f'{where}: {what}: not an array ({e})') from None
  if array.dtype.kind not in kinds:
    raise DeployError(f'{where}: {what} of {array.dtype} values; '
                      f'{"real numbers" if "f" in kinds else "unsigned 8-bit or 0..1 floats"} '
                      'expected')
  return array


def points(depth: np.ndarray, camera: Camera, calibration: Calibration, where: str):
  """(N, 3) workspace-frame points of a depth image (metres), with their pixel indices."""
  if depth.shape != (camera.height, camera.width):
    raise DeployError(f'{where}: depth image of {depth.shape[1]}x{depth.shape[0]} pixels, its '
                      f'calibration says {camera.width}x{camera.height}')
  valid = np.isfinite(depth) & (depth > 0)
  if not valid.any():
    raise DeployError(f'{where}: no valid depth in the image (a camera that returned nothing)')
  v, u = np.nonzero(valid)
  d = depth[v, u]
  cam = np.stack([(u - camera.cx) / camera.fx * d, (v - camera.cy) / camera.fy * d, d,
                  np.ones_like(d)])
  world = calibration.base_to_workspace() @ camera.camera_to_base @ cam
  return world[:3].T, v * camera.width + u


def heightmaps(depths, calibration: Calibration, colors=None):
  """(color (V, R, R, 3) in 0..1, depth (V, R, R) m, seen (V, R, R)) of one depth image per
  camera of `calibration` (metres, (height, width)) and, optionally, one colour image each
  (RGB, uint8 or 0..1; none: colour 0)."""
  for name, images in (('depths', depths), ('colors', colors)):
    if not isinstance(images, (list, tuple, np.ndarray)) and (name, images) != ('colors', None):
      raise DeployError(f'{name}={images!r:.40}: a list of one image per camera expected')
  if len(depths) != len(calibration.cameras):
    raise DeployError(f'{len(depths)} depth images for {len(calibration.cameras)} cameras')
  if colors is not None and len(colors) != len(depths):
    raise DeployError(f'{len(colors)} colour images for {len(depths)} depth images')
  r, half, res = calibration.grid, calibration.half, calibration.resolution
  out_color = np.zeros((len(depths), r, r, 3), np.float32)
  out_depth = np.zeros((len(depths), r, r), np.float32)
  out_seen = np.zeros((len(depths), r, r), bool)
  for i, (depth, camera) in enumerate(zip(depths, calibration.cameras)):
    where = f'camera {camera.name}'
    depth = _array(depth, 'uif', where, 'depth image').astype(np.float64)
    if depth.ndim != 2:
      raise DeployError(f'{where}: depth image of shape {depth.shape}; (height, width) expected')
    xyz, pixel = points(depth, camera, calibration, where)
    cell, height = binned(xyz[:, 0], xyz[:, 1], xyz[:, 2], True, res, half, calibration.top)
    keep = cell >= 0
    cell, height = cell[keep], height[keep]
    best = np.full(r * r, -1, np.int32)
    np.maximum.at(best, cell, height)
    seen = best >= 0
    out_seen[i] = seen.reshape(r, r)
    out_depth[i] = np.where(seen, best * HEIGHT_UNIT, 0.0).reshape(r, r)
    if colors is not None:
      image = _array(colors[i], 'uf', where, 'colour image')
      if image.shape[:2] != depth.shape or image.ndim != 3 or image.shape[2] != 3:
        raise DeployError(f'{where}: colour image of shape {image.shape}, its depth image is '
                          f'{depth.shape[1]}x{depth.shape[0]} (RGB expected)')
      if image.dtype.kind == 'u' and image.dtype != np.uint8 or image.dtype.kind == 'f' and not (
          np.isfinite(image).all() and 0 <= image.min() and image.max() <= 1):
        raise DeployError(f'{where}: colour image of {image.dtype} values from {image.min()} to '
                          f'{image.max()}: uint8, or finite floats in 0..1, expected')
      rgb = image.reshape(-1, 3)[pixel[keep]].astype(np.float32)
      rgb = rgb / 255.0 if image.dtype == np.uint8 else rgb
      top = height == best[cell]  # the colour of the highest point of its cell
      flat = out_color[i].reshape(-1, 3)
      flat[cell[top]] = rgb[top]
  return out_color, out_depth, out_seen
