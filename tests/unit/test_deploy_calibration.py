"""Calibration files, images and the deploy package's independence from JAX: every bad input is
one line naming the file and the field."""
import copy
import json
import subprocess
import sys

import numpy as np
import pytest

from mvcoba_jax.deploy import DeployError, heightmaps, load_calibration

GOOD = {'workspace': {'center': [0.5, 0.0, 0.02], 'yaw_deg': 0.0, 'half': 0.224, 'top': 0.4,
                      'resolution': 0.004},
        'cameras': [{'name': 'left', 'width': 64, 'height': 48, 'fx': 60.0, 'fy': 60.0,
                     'cx': 31.5, 'cy': 23.5, 'depth_scale': 0.001,
                     'camera_to_base': [[1, 0, 0, 0.5], [0, -1, 0, 0], [0, 0, -1, 0.6],
                                        [0, 0, 0, 1]]}]}


def write(tmp_path, data, name='cal.json'):
  path = tmp_path / name
  path.write_text(json.dumps(data) if not isinstance(data, str) else data)
  return path


@pytest.mark.parametrize('edit, says', [
    (lambda d: d['cameras'][0].pop('fx'), 'cameras[0].fx: missing'),
    (lambda d: d['cameras'][0].update(fx=-3), 'cameras[0].fx'),
    (lambda d: d['cameras'][0].update(K=[[60, 0, 31.5], [0, 60, 23.5], [0, 0, 1]]),
     'give K or fx, fy, cx, cy, not both'),
    (lambda d: d['cameras'][0].update(camera_to_base=[[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0],
                                                       [0, 0, 0, 1]]), 'not a rigid transform'),
    (lambda d: d['cameras'][0].update(camera_to_base=[[1, 0], [0, 1]]), 'expected a 4x4 matrix'),
    (lambda d: d['cameras'][0].update(camera_to_base=[[str(v) for v in r] for r in
                                                      d['cameras'][0]['camera_to_base']]),
     'expected a 4x4 matrix of numbers'),
    (lambda d: d['cameras'][0].update(depth_scale=0), 'cameras[0].depth_scale'),
    (lambda d: d['cameras'][0].update(width=2.5), 'cameras[0].width'),
    (lambda d: d['cameras'][0].update(lens='wide'), "unknown field 'lens'"),
    (lambda d: d['workspace'].update(resolution=0.003), 'does not tile'),
    (lambda d: d['workspace'].pop('center'), 'workspace: fields'),
    (lambda d: d.update(cameras=[]), 'at least one camera'),
])
def test_bad_calibration_is_one_line_naming_the_field(tmp_path, edit, says):
  data = copy.deepcopy(GOOD)
  edit(data)
  with pytest.raises(DeployError) as error:
    load_calibration(write(tmp_path, data))
  assert says in str(error.value) and str(tmp_path / 'cal.json') in str(error.value)
  assert '\n' not in str(error.value)


def test_k_matrix_stands_for_the_intrinsics_and_bad_files_are_named(tmp_path):
  data = copy.deepcopy(GOOD)
  for key in ('fx', 'fy', 'cx', 'cy'):
    data['cameras'][0].pop(key)
  data['cameras'][0]['K'] = [[60, 0, 31.5], [0, 60, 23.5], [0, 0, 1]]
  camera = load_calibration(write(tmp_path, data)).cameras[0]
  assert (camera.fx, camera.fy, camera.cx, camera.cy) == (60, 60, 31.5, 23.5)
  with pytest.raises(DeployError, match='cannot read a calibration'):
    load_calibration(write(tmp_path, '{', 'broken.json'))


def test_wrong_image_sizes_and_empty_depth_are_refused(tmp_path):
  cal = load_calibration(write(tmp_path, GOOD))
  with pytest.raises(DeployError, match='camera left: depth image of 10x10 pixels, its '
                                        'calibration says 64x48'):
    heightmaps([np.ones((10, 10))], cal)
  with pytest.raises(DeployError, match='camera left: no valid depth'):
    heightmaps([np.zeros((48, 64))], cal)
  with pytest.raises(DeployError, match='2 depth images for 1 cameras'):
    heightmaps([np.ones((48, 64))] * 2, cal)
  with pytest.raises(DeployError, match='3 colour images for 1 depth images'):
    heightmaps([np.ones((48, 64))], cal, [np.zeros((48, 64, 3), np.uint8)] * 3)
  _, depth, seen = heightmaps([np.full((48, 64), 0.58)], cal)  # a flat table 2 cm below: height 0
  assert seen.any() and np.abs(depth[seen]).max() == 0.0


@pytest.mark.parametrize('depths, colors, says', [
    (None, None, 'depths=None: a list of one image per camera'),
    ([None], None, 'depth image of object values; real numbers expected'),
    (['far'], None, 'depth image of <U3 values; real numbers expected'),
    ([np.ones(64)], None, r'depth image of shape \(64,\)'),
    ([np.ones((48, 64), complex)], None, 'depth image of complex128 values'),
    ([np.full((48, 64), 0.58).tolist()], [np.zeros((48, 64, 3)).tolist()], None),
    ([np.ones((48, 64))], [np.zeros((48, 64, 3), bool)], 'colour image of bool values'),
    ([np.ones((48, 64))], [np.full((48, 64, 3), np.nan)], 'colour image of float64 values from '
                                                         'nan'),
    ([np.ones((48, 64))], [np.full((48, 64, 3), 255.0)], 'finite floats in 0..1'),
    ([np.ones((48, 64))], [np.zeros((48, 64, 3), np.uint16)], 'uint8, or finite floats'),
    ([np.ones((48, 64))], 'rgb', "colors='rgb': a list of one image per camera"),
])
def test_images_of_the_wrong_kind_are_refused_in_one_line(tmp_path, depths, colors, says):
  """Depth and colour images come as lists of real-valued arrays of the camera's size, colour as
  uint8 or finite 0..1 floats; anything else is one DeployError naming the camera, not a
  traceback or colour read from NaN. Lists of numbers are arrays like any other."""
  cal = load_calibration(write(tmp_path, GOOD))
  if says is None:
    _, _, seen = heightmaps(depths, cal, colors)
    assert seen.any()
    return
  with pytest.raises(DeployError, match=says):
    heightmaps(depths, cal, colors)


def test_a_depth_image_read_as_colour_is_refused(tmp_path):
  """read_color takes 8-bit colour files (BGR or BGRA) and refuses a 16-bit or one-channel one,
  the depth image given in its place."""
  import cv2
  from mvcoba_jax.deploy.heightmaps import read_color
  cv2.imwrite(str(tmp_path / 'depth.png'), np.full((48, 64), 600, np.uint16))
  with pytest.raises(DeployError, match='3 channels of 8 bits, this one 1 of 16 .a depth image'):
    read_color(tmp_path / 'depth.png')
  cv2.imwrite(str(tmp_path / 'rgba.png'), np.dstack([np.zeros((48, 64, 2), np.uint8),
                                                     np.full((48, 64, 2), 255, np.uint8)]))
  rgb = read_color(tmp_path / 'rgba.png')
  assert rgb.shape == (48, 64, 3) and (rgb[..., 0] == 255).all() and (rgb[..., 2] == 0).all()


def test_the_deploy_package_imports_without_jax_or_mujoco():
  code = ('import sys; sys.modules["jax"] = None; sys.modules["mujoco"] = None\n'
          'import mvcoba_jax.deploy\nprint("ok")')
  out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, timeout=60)
  assert out.stdout.strip() == 'ok', out.stderr[-400:]


def test_fuzzed_image_arguments_are_refused_in_one_line_or_accepted(tmp_path):
  """Generated arguments to heightmaps() (fixed seed): odd values, shapes and dtypes for the
  depth and colour lists, each answered by heightmaps of the grid or one DeployError line."""
  import random
  rng = random.Random(0)
  cal = load_calibration(write(tmp_path, GOOD))
  good_depth, good_color = np.full((48, 64), 0.58), np.zeros((48, 64, 3), np.uint8)
  odd = [None, 'x', 0, 1.5, True, [], {}, np.nan, np.zeros(0), np.zeros((48, 64, 3)),
         np.full((48, 64), np.inf), np.full((48, 64), -1.0), np.ones((48, 64), np.int16),
         np.ones((48, 64), complex), np.zeros((48, 64), object), good_depth.tolist(),
         np.zeros((48, 64, 3), np.float32) + 2, np.zeros((64, 48, 3), np.uint8), good_color,
         good_depth]
  outcomes = {'ok': 0, 'refused': 0}
  for _ in range(300):
    depths = rng.choice([[good_depth], [rng.choice(odd)], rng.choice(odd), [good_depth] * 2])
    colors = rng.choice([None, [good_color], [rng.choice(odd)], rng.choice(odd)])
    try:
      color, depth, seen = heightmaps(depths, cal, colors)
    except DeployError as e:
      assert '\n' not in str(e) and len(str(e)) < 300, str(e)
      outcomes['refused'] += 1
      continue
    assert color.shape == (1, 112, 112, 3) and depth.shape == seen.shape == (1, 112, 112)
    assert np.isfinite(color).all() and 0 <= color.min() and color.max() <= 1
    outcomes['ok'] += 1
  assert outcomes['ok'] > 10 and outcomes['refused'] > 100, outcomes
