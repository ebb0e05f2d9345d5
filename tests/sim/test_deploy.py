"""The deploy path against the training pipeline: depth images that the simulator's cameras
render, written as 16-bit PNG files in millimetres with their true intrinsics and poses, give
the heightmaps training builds of the same scenes, in any base frame the calibration names."""
import math

import cv2
import jax
import mujoco
import numpy as np
import pytest

from mvcoba_jax.deploy import calibration_from_dict, heightmaps, read_depth
from mvcoba_jax.learner import task
from mvcoba_jax.sim import cameras
from tests.helpers import make_env


@pytest.fixture(scope='module')
def scenes():
  """(env, 6 settled drops with occluders on a third, their camera images, their heightmaps)."""
  env = make_env('default', 'native', 'env.occluded_share=0.3')
  states = jax.jit(jax.vmap(env.reset))(jax.random.split(jax.random.PRNGKey(4), 6))
  images = jax.jit(jax.vmap(lambda s: cameras.render(env, s)))(states)
  observed = jax.jit(lambda s: task.observe(env, s))(states)
  return env, states, images, observed


def camera_poses(env) -> list[np.ndarray]:
  """Each camera's pose as OpenCV sees it (x right, y down, looking along +z), 4x4, in the
  simulator's world (= the workspace frame)."""
  data = mujoco.MjData(env.scene.mj_model)
  mujoco.mj_kinematics(env.scene.mj_model, data)
  mujoco.mj_camlight(env.scene.mj_model, data)
  poses = []
  for c in range(len(env.config.scene.cameras)):
    pose = np.eye(4)
    pose[:3, :3] = data.cam_xmat[c].reshape(3, 3) @ np.diag([1.0, -1.0, -1.0])
    pose[:3, 3] = data.cam_xpos[c]
    poses.append(pose)
  return poses


def calibration(env, base_from_workspace=np.eye(4), yaw_deg=0.0) -> dict:
  config = env.config
  cams = []
  for cam, pose in zip(config.scene.cameras, camera_poses(env)):
    f = cameras.focal_length(cam)
    cams.append({'name': f'cam{len(cams)}', 'width': cam.width, 'height': cam.height, 'fx': f,
                 'fy': f, 'cx': cam.width / 2 - 0.5, 'cy': cam.height / 2 - 0.5,
                 'camera_to_base': (base_from_workspace @ pose).tolist(), 'depth_scale': 0.001})
  return {'workspace': {'center': base_from_workspace[:3, 3].tolist(), 'yaw_deg': yaw_deg,
                        'half': config.scene.workspace_half, 'top': config.scene.workspace_top,
                        'resolution': config.perception.heightmap_resolution},
          'cameras': cams}


def test_heightmaps_from_16_bit_png_depth_match_training(scenes, tmp_path):
  """Metres as rendered give training's heightmaps to a 10 um height step; 16-bit millimetre
  PNGs give at least 99% of cells within 2 mm (the millimetre steps move a point across a 4 mm
  cell's edge now and then), in the simulator's frame and in a base frame 0.5 m away and turned
  30 degrees."""
  env, _, images, observed = scenes
  yaw = 30.0
  c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
  base = np.array([[c, -s, 0, 0.5], [s, c, 0, -0.1], [0, 0, 1, 0.02], [0, 0, 0, 1]])
  for frame in (calibration(env), calibration(env, base, yaw)):  # two base frames, one result
    cal = calibration_from_dict(frame)
    close = []
    for b in range(images[0].depth.shape[0]):
      want_depth, want_seen = np.asarray(observed.depth[b]), np.asarray(observed.seen[b])
      metres = [np.asarray(image.depth[b], np.float64) for image in images]
      _, depth, seen = heightmaps(metres, cal)
      assert (seen == want_seen).all() and np.abs(depth - want_depth).max() < 2.5e-5  # a step
      pngs = []
      for v, image in enumerate(metres):
        path = tmp_path / f'd{b}-{v}.png'
        cv2.imwrite(str(path), np.round(image * 1000).astype(np.uint16))
        pngs.append(read_depth(path, cal.cameras[v]))
      _, depth, _ = heightmaps(pngs, cal)
      close.append(np.abs(depth - want_depth) <= 0.002)
      assert want_seen.mean() > 0.5
    assert np.mean(close) >= 0.99 and min(c.mean() for c in close) >= 0.98, np.mean(close)
