"""The deploy path against the training pipeline: depth images that the simulator's cameras
render, written as 16-bit PNG files in millimetres with their true intrinsics and poses, give
the heightmaps training builds of the same scenes, in any base frame the calibration names."""
import importlib.util
import json
import math
import pathlib
import shutil
import subprocess
import sys

import cv2
import jax
import numpy as np
import pytest

from mvcoba_jax import export, policy
from mvcoba_jax.config import resolve
from mvcoba_jax.deploy import (DeployError, OnnxPolicy, calibration_from_dict, heightmaps,
                               read_color, read_depth)
from mvcoba_jax.sim import cameras
from tests.helpers import make_env, make_task

ROOT = pathlib.Path(__file__).resolve().parents[2]
RESOLUTION = resolve('default').perception.heightmap_resolution  # the reproduction's too
# jax2onnx's GroupNorm plugin reads Variable.value, which Flax deprecates.
pytestmark = pytest.mark.filterwarnings('ignore::DeprecationWarning:jax2onnx')


@pytest.fixture(scope='module')
def scenes():
  """(env, 16 settled drops with occluders on a third, their camera images, their heightmaps)."""
  task = make_task('reproduction', 'native', 'env.occluded_share=0.3')
  env = task.env
  states = jax.jit(jax.vmap(env.reset))(jax.random.split(jax.random.PRNGKey(4), 16))
  images = jax.jit(jax.vmap(lambda s: cameras.render(env, s)))(states)
  observed = jax.jit(task.observe)(states)
  return env, states, images, observed


def calibration(env, base_from_workspace=np.eye(4), yaw_deg=0.0) -> dict:
  """The simulator's calibration (`cameras.calibration`) with its workspace placed in a base
  frame by `base_from_workspace` (4x4, turned by `yaw_deg`), depth in millimetres."""
  data = cameras.calibration(env, RESOLUTION)
  for cam in data['cameras']:
    cam['camera_to_base'] = (base_from_workspace @ np.asarray(cam['camera_to_base'])).tolist()
    cam['depth_scale'] = 0.001
  data['workspace'].update(center=base_from_workspace[:3, 3].tolist(), yaw_deg=yaw_deg)
  return data


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
    close, seen_share = [], []
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
      seen_share.append(want_seen.mean())
    assert np.mean(seen_share) > 0.5 and np.mean(close) >= 0.99 and min(c.mean() for c in close) >= 0.98, np.mean(close)


@pytest.fixture(scope='module')
def onnx(tmp_path_factory):
  """The shipped MV-COBA policy exported with its ONNX graph, as a deploy policy."""
  out = tmp_path_factory.mktemp('export') / 'mvcoba'
  return OnnxPolicy(export.export(ROOT / 'pretrained' / 'mvcoba', out)['onnx'].parent)


def png_heightmaps(images, b, cal, folder):
  """The heightmaps of scene `b` from its cameras' depth written and read back as 16-bit PNG, and
  their colour images as 8-bit RGB."""
  depths, colors = [], []
  for v, image in enumerate(images):
    path = folder / f'a{b}-{v}.png'
    cv2.imwrite(str(path), np.round(np.asarray(image.depth[b]) * 1000).astype(np.uint16))
    depths.append(read_depth(path, cal.cameras[v]))
    colors.append(np.round(np.asarray(image.rgb[b]) * 255).astype(np.uint8))
  return heightmaps(depths, cal, colors)


def test_the_exported_policy_on_camera_images_acts_as_the_jax_policy(scenes, onnx, tmp_path):
  """The shipped MV-COBA exported to ONNX, in a base frame turned 90 degrees, over 16 scenes each
  after a change and after none (32 states): on heightmaps from the cameras' exact depth and
  colour it takes the JAX policy's action on training's heightmaps in all 32; on heightmaps
  from 16-bit PNG depth it takes the JAX policy's action on those same heightmaps in at least 31
  (the millimetre steps alone move the argmax of near-equal Q values in about a third of these
  states: docs/deploy.md); positions and angles are carried into the base frame, a push with the
  length it trained with (cut short only at the workspace's edge, as the JAX policy cuts it); a frame a camera saw nothing
  of and a grid of another size are refused."""
  env, _, images, observed = scenes
  jax_policy = policy.load(ROOT / 'pretrained' / 'mvcoba')
  base = np.array([[0, -1, 0, 0.4], [1, 0, 0, 0.1], [0, 0, 1, 0.0], [0, 0, 0, 1]])
  cal = calibration_from_dict(calibration(env, base, 90.0))
  key = lambda a: (a.primitive, a.rotation, a.row, a.col)
  exact, quantised = [], []
  for b in range(16):
    metres = heightmaps([np.asarray(im.depth[b], np.float64) for im in images], cal,
                        [np.asarray(im.rgb[b]) for im in images])
    color, depth, seen = png_heightmaps(images, b, cal, tmp_path)
    for changed in (True, False):
      want = jax_policy.act(np.asarray(observed.color[b]), np.asarray(observed.depth[b]),
                            changed, seen=np.asarray(observed.seen[b]))
      action = onnx.act(*metres, changed, cal)
      exact.append(key(action) == key(want))
      trained = jax_policy.config.env.push_length if action.primitive == 'push' else 0.0
      cell = [-cal.half + (i + 0.5) * cal.resolution for i in (action.col, action.row)]
      inside = max(abs(v) for v in cell) < cal.half - trained  # no edge within a push's reach
      assert action.push_length == trained if inside else 0 <= action.push_length <= trained
      if exact[-1]:  # one push contract: both policies cut a push the same way
        assert math.isclose(action.push_length, want.push_length, abs_tol=1e-9)
        x, y, _ = want.position
        np.testing.assert_allclose(action.position[:2], (0.4 - y, 0.1 + x), atol=1e-6)
        assert math.isclose(math.remainder(action.angle - want.angle - math.pi / 2, 2 * math.pi),
                            0.0, abs_tol=1e-6)
      quantised.append(key(onnx.act(color, depth, seen, changed, cal))
                       == key(jax_policy.act(color, depth, changed, seen=seen)))
  assert sum(exact) == 32 and sum(quantised) >= 31, (sum(exact), sum(quantised))
  with pytest.raises(DeployError, match='refused: camera cam0 sees none'):
    onnx.act(color, depth, np.stack([np.zeros_like(seen[0]), seen[1]]), True, cal)
  coarse = calibration(env, base, 90.0)
  coarse['workspace']['resolution'] = 0.008
  with pytest.raises(DeployError, match='is not the policy'):
    onnx.act(color, depth, seen, True, calibration_from_dict(coarse))


def test_change_between_frames_is_observed_as_training_observes_it(scenes, onnx, tmp_path):
  """Two different scenes differ; a scene and itself do not (the change rule of model.json)."""
  env, _, images, _ = scenes
  cal = calibration_from_dict(calibration(env))
  first, second = (png_heightmaps(images, b, cal, tmp_path) for b in (0, 1))
  assert onnx.changed(first[1:], second[1:]) and not onnx.changed(first[1:], first[1:])


def test_the_robot_loop_example_runs_against_the_simulator(onnx):
  """examples/robot_loop.py with the simulated rig: five rounds of capture, act, execute and
  change observation; the policy picks objects off the table."""
  spec = importlib.util.spec_from_file_location('robot_loop', ROOT / 'examples' / 'robot_loop.py')
  example = importlib.util.module_from_spec(spec)
  spec.loader.exec_module(example)
  rig = example.SimulatedRig(onnx.spec.config, seed=3)
  before = rig.objects()
  records = example.run(rig, onnx, calibration_from_dict(rig.calibration), 5, say=lambda _: None)
  assert len(records) == 5 and all('primitive' in r for r in records)
  assert rig.objects() < before and any(r['changed'] for r in records)


def test_the_deploy_api_takes_a_plain_yes_or_no_as_the_jax_policy_does(scenes, onnx):
  """The same `changed` values to `Policy.act` and `OnnxPolicy.act`: numpy's booleans act as
  Python's, the same action on both; anything else ('no', None, [], 0, a 0-d array) is refused by
  both in one line. `OnnxPolicy.changed`: a gripper's np.False_ applies the failed-grasp rule as
  False does; a reading that is no boolean, or failed grasps that are no whole number, refused.
  A view the network reads that saw nothing is refused by both."""
  env, _, _, observed = scenes
  jax_policy = policy.load(ROOT / 'pretrained' / 'mvcoba')
  cal = calibration_from_dict(calibration(env))
  color, depth, seen = (np.asarray(a[0]) for a in (observed.color, observed.depth, observed.seen))
  for flag in (True, np.True_, np.False_):
    want = jax_policy.act(color, depth, flag, seen=seen)
    got = onnx.act(color, depth, seen, flag, cal)
    assert (got.primitive, got.rotation, got.row, got.col) == (
        want.primitive, want.rotation, want.row, want.col)
  for bad in ('no', None, [], 0, np.asarray(True)):
    with pytest.raises(policy.PolicyError, match='True or False'):
      jax_policy.act(color, depth, bad, seen=seen)
    with pytest.raises(DeployError, match=r'^changed=.*: True or False'):
      onnx.act(color, depth, seen, bad, cal)
  blind = seen.copy()
  blind[1] = False  # a camera that saw nothing: refused by both, not filled from the other
  with pytest.raises(policy.PolicyError, match='view 1 sees none of the workspace'):
    jax_policy.act(color, depth, True, seen=blind)
  with pytest.raises(DeployError, match='camera .* sees none of the workspace'):
    onnx.act(color, depth, blind, True, cal)
  frame = (depth, seen)
  assert onnx.changed(frame, frame, grasped=np.True_) is True
  retries = onnx.spec.failed_grasp_retries
  assert onnx.changed(frame, frame, grasped=np.False_, failures=np.int64(retries)) is False
  for bad in ('no', 0, np.asarray(False)):
    with pytest.raises(DeployError, match=r'^grasped=.*: True or False'):
      onnx.changed(frame, frame, grasped=bad)
  for bad in (-1, 1.5, '1', None, True):
    with pytest.raises(DeployError, match=r'^failures=.*: a whole number'):
      onnx.changed(frame, frame, grasped=False, failures=bad)


def test_the_policy_carries_its_gripper_and_refuses_another(onnx, capsys):
  """model.json names the gripper the policy trained with; a grasp carries its opening; the
  robot loop refuses a robot with another gripper in one line, unless told to act anyway."""
  assert onnx.gripper['name'] == 'rg2' and onnx.gripper['max_opening'] == 0.11
  OnnxPolicy(onnx.folder, gripper='rg2')
  OnnxPolicy(onnx.folder, gripper=dict(onnx.gripper))
  for other in ('robotiq_2f85', {**onnx.gripper, 'max_opening': 0.085}):
    with pytest.raises(DeployError, match="trained with gripper 'rg2' .opening 0.11 m., the robot"):
      OnnxPolicy(onnx.folder, gripper=other)
  spec = importlib.util.spec_from_file_location('robot_loop', ROOT / 'examples' / 'robot_loop.py')
  example = importlib.util.module_from_spec(spec)
  spec.loader.exec_module(example)
  assert example.main(['--model', str(onnx.folder), '--actions', '1',
                       '--gripper', 'franka_hand']) == 2
  assert capsys.readouterr().err.count('\n') == 1
  assert example.main(['--model', str(onnx.folder), '--actions', '3', '--gripper', 'franka_hand',
                       '--other-gripper']) == 0
  rounds = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
  assert all(r['opening'] == (0.11 if r['primitive'] == 'grasp' else 0.0) for r in rounds)


def test_the_deploy_extra_alone_turns_camera_files_into_the_same_action(scenes, onnx, tmp_path):
  """In a fresh virtualenv holding only `pip install '.[deploy]'` (numpy, OpenCV, onnxruntime:
  no JAX, no MuJoCo), examples/camera_action.py turns a scene's 16-bit PNG depth and colour files
  and their calibration into the action this process's deploy path takes, and a command of the
  package says in one line that it needs the train extra."""
  env, _, images, _ = scenes
  cal_file = tmp_path / 'calibration.json'
  cal_file.write_text(json.dumps(calibration(env)))
  cal = calibration_from_dict(calibration(env))
  depth_files, color_files, colors = [], [], []
  for v, image in enumerate(images):
    depth_files.append(tmp_path / f'depth{v}.png')
    cv2.imwrite(str(depth_files[-1]), np.round(np.asarray(image.depth[2]) * 1000).astype(np.uint16))
    color_files.append(tmp_path / f'color{v}.png')
    colors.append(np.round(np.asarray(image.rgb[2]) * 255).astype(np.uint8))
    cv2.imwrite(str(color_files[-1]), cv2.cvtColor(colors[-1], cv2.COLOR_RGB2BGR))
    np.testing.assert_array_equal(read_color(color_files[-1]), colors[-1])  # RGB, as written
  want = onnx.act(*heightmaps([read_depth(f, c) for f, c in zip(depth_files, cal.cameras)], cal,
                              colors), False, cal)

  source = tmp_path / 'source'  # the project's files a wheel is built from, not the work tree
  shutil.copytree(ROOT / 'mvcoba_jax', source / 'mvcoba_jax',
                  ignore=shutil.ignore_patterns('__pycache__'))
  for name in ('pyproject.toml', 'README.md', 'LICENSE'):
    shutil.copy(ROOT / name, source / name)
  venv = tmp_path / 'venv'
  subprocess.run([sys.executable, '-m', 'venv', str(venv)], check=True)
  python = str(venv / 'bin' / 'python')
  installed = subprocess.run([python, '-m', 'pip', 'install', '-q', f'{source}[deploy]'],
                             capture_output=True, text=True, timeout=900)
  assert installed.returncode == 0, installed.stderr[-2000:]
  for name in ('jax', 'mujoco', 'flax'):
    assert subprocess.run([python, '-c', f'import {name}'], capture_output=True).returncode != 0
  out = subprocess.run(
      [python, str(ROOT / 'examples' / 'camera_action.py'), '--calibration', str(cal_file),
       '--model', str(onnx.folder), '--depth', *map(str, depth_files),
       '--color', *map(str, color_files), '--changed', '0'],
      capture_output=True, text=True, timeout=300, cwd=tmp_path)
  assert out.returncode == 0, out.stderr[-2000:]
  got = json.loads(out.stdout)
  assert (got['primitive'], got['rotation'], got['row'], got['col']) == (
      want.primitive, want.rotation, want.row, want.col)
  np.testing.assert_allclose(got['position'], want.position, atol=1e-9)
  refused = subprocess.run([str(venv / 'bin' / 'mvcoba-train')], capture_output=True, text=True)
  assert refused.returncode == 2 and refused.stderr.count('\n') == 1, refused.stderr
  assert "pip install 'mvcoba-jax[train]'" in refused.stderr


def fuzzed_observations(seed: int = 0):
  """(what, colour, depth) of the example state broken in the ways a lab's pipeline breaks it,
  with a fixed seed: non-finite cells, other units, grids, views and dtypes, and valid
  variants (uint8 and uint16 colour, NaN cells treated as unseen)."""
  state = np.load(ROOT / 'pretrained' / 'example-state.npz')
  color, depth = state['color'], state['depth']
  rng = np.random.default_rng(seed)
  cells = lambda a, v: np.where(rng.random(a.shape) < 0.01, v, a).astype(a.dtype)
  yield 'as saved', color, depth
  yield 'NaN depth cells', color, cells(depth, np.nan)
  yield 'infinite depth cells', color, cells(depth, np.inf)
  yield '-inf depth cells', color, cells(depth, -np.inf)
  yield 'all depth NaN', color, np.full_like(depth, np.nan)
  yield 'NaN colour', np.full_like(color, np.nan), depth
  yield 'NaN colour cells', cells(color, np.nan), depth
  yield 'depth in mm', color, depth * 1000
  yield 'negative depth', color, depth - 0.05
  yield 'uint8 colour', np.round(color * 255).astype(np.uint8), depth
  yield 'uint16 colour', np.round(color * 65535).astype(np.uint16), depth
  yield 'float 0-255 colour', color * 255, depth
  yield 'float64 lists', color.astype(np.float64).tolist(), depth.tolist()
  yield 'one view', color[:1], depth[:1]
  yield 'three views', np.concatenate([color, color[:1]]), np.concatenate([depth, depth[:1]])
  yield 'a 224 grid', color.repeat(2, 1).repeat(2, 2), depth.repeat(2, 1).repeat(2, 2)
  yield 'a 56 grid', color[:, ::2, ::2], depth[:, ::2, ::2]
  yield 'grey colour', color[..., 0], depth
  yield 'strings', color.astype(str), depth
  yield 'booleans', color > 0.5, depth > 0
  yield 'complex depth', color, depth.astype(np.complex64)
  yield 'ragged lists', color, [depth[0].tolist(), depth[1, :5].tolist()]
  yield 'random heights', color, rng.uniform(-0.01, 0.5, depth.shape).astype(np.float32)
  for i in range(8):  # plausible noise: valid or refused, never acted on wrongly
    yield f'noise {i}', rng.random(color.shape, np.float32), rng.uniform(
        0, 0.3, depth.shape).astype(np.float32)


def test_fuzzed_observations_are_refused_or_give_a_safe_action(onnx):
  """Every broken observation is refused with one line, or the JAX policy and the exported one
  both act finitely inside the workspace above the table; a NaN cell is unseen, never fed on
  (the action with NaN cells is the action with those cells at 0)."""
  jax_policy = policy.load(ROOT / 'pretrained' / 'mvcoba')
  cal = calibration_from_dict(calibration(make_env('default', 'native')))
  half, top = cal.half, cal.top
  outcomes = {'acted': 0, 'refused': 0}
  seen = np.ones((2, 112, 112), bool)
  for what, color, depth in fuzzed_observations():
    for name, act in (('jax', lambda: jax_policy.act(color, depth, True, seen=seen)),
                      ('onnx', lambda: onnx.act(color, depth, seen, True, cal))):
      try:
        a = act()
      except (policy.PolicyError, DeployError) as e:
        assert '\n' not in str(e) and len(str(e)) < 300, (what, name, str(e))
        outcomes['refused'] += 1
        continue
      x, y, z = a.position if name == 'jax' else (
          cal.base_to_workspace() @ np.append(a.position, 1.0))[:3]
      assert math.isfinite(a.q) and math.isfinite(a.angle), (what, name, a)
      assert abs(x) <= half + 1e-6 and abs(y) <= half + 1e-6, (what, name, a)
      assert -1e-6 <= z <= top + 1e-6, (what, name, a)
      outcomes['acted'] += 1
  assert outcomes['acted'] >= 12 and outcomes['refused'] >= 20, outcomes
  state = np.load(ROOT / 'pretrained' / 'example-state.npz')
  broken = state['depth'].copy()
  broken[:, 10:20, 10:20] = np.nan
  zeroed = np.nan_to_num(broken, nan=0.0)
  seen = state['seen']
  assert (jax_policy.act(state['color'], broken, seen=seen)
          == jax_policy.act(state['color'], zeroed, seen=seen))
  assert jax_policy.act(state['color'], state['depth'], False, seen=seen).primitive == 'push'
  with pytest.raises(policy.PolicyError, match='changed='):
    jax_policy.act(state['color'], state['depth'], changed='yes', seen=seen)


def test_a_network_that_scores_nan_is_never_acted_on():
  """Parameters damaged after loading (a NaN weight): every Q is NaN, the argmax would be a grasp
  at the workspace's corner; the policy refuses instead."""
  from flax import nnx  # noqa: PLC0415
  loaded = policy.load(ROOT / 'pretrained' / 'mvcoba')
  state = nnx.state(loaded.network, nnx.Param)
  leaves, tree = jax.tree.flatten(state)
  nnx.update(loaded.network, jax.tree.unflatten(tree, [leaves[0] * np.nan] + leaves[1:]))
  example = np.load(ROOT / 'pretrained' / 'example-state.npz')
  with pytest.raises(policy.PolicyError, match='action refused: the network scored the action nan'):
    loaded.act(example['color'], example['depth'], seen=example['seen'])


def test_a_failed_grasp_is_no_change_for_a_policy_trained_so(scenes, onnx):
  """`changed` as training observes it: a grasp that held something is a change whatever the
  frames show; a grasp that held nothing is no change for a policy trained with
  `perception.failed_grasp_changes=false`, whatever it moved, past its
  `failed_grasp_retries` such grasps in a row, and the frames decide otherwise."""
  import copy
  import dataclasses
  env, _, _, observed = scenes
  before = (np.asarray(observed.depth[0]), np.asarray(observed.seen[0]))
  after = (np.asarray(observed.depth[1]), np.asarray(observed.seen[1]))  # another drop: moved
  paper = copy.copy(onnx)  # the shipped default trained with failed_grasp_changes=false
  paper.spec = dataclasses.replace(onnx.spec, failed_grasp_changes=True)
  assert paper.changed(before, after)
  assert paper.changed(before, before, grasped=True) and not paper.changed(before, before)
  assert paper.changed(before, after, grasped=False)  # the paper's rule: the frames decide
  assert not onnx.spec.failed_grasp_changes and not onnx.changed(before, after, grasped=False)
  assert onnx.changed(before, after) and onnx.changed(before, before, grasped=True)
  retrying = OnnxPolicy(onnx.folder, failed_grasp_retries=1)  # acting under another rule
  assert retrying.spec == dataclasses.replace(onnx.spec, failed_grasp_retries=1)
  assert retrying.changed(before, after, grasped=False)  # the first: the frames decide
  assert not retrying.changed(before, before, grasped=False)
  assert not retrying.changed(before, after, grasped=False, failures=1)
  with pytest.raises(DeployError, match='two frames of one shape'):
    onnx.changed(before, (after[0][:, :50], after[1][:, :50]))
  with pytest.raises(DeployError, match='seen as booleans'):
    onnx.changed(before, (after[0], after[1].astype(np.float32)))
