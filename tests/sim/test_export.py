"""Export: params.npz round trip, ONNX parity with onnxruntime on random and
rendered heightmaps, the example script's action, and clear errors for bad work directories."""
import dataclasses
import importlib.util
import json
import pathlib
import shutil
import subprocess
import sys
import time
import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from flax import nnx

import mvcoba_jax
from mvcoba_jax import export, perception, policy
from mvcoba_jax.cli import export as export_cli
from mvcoba_jax.cli import viz as viz_cli
from mvcoba_jax.config import ConfigError, defaulted, from_dict, resolve, to_dict
from mvcoba_jax.learner import agent
from mvcoba_jax.learner.checkpoint import Checkpoints
from mvcoba_jax.learner.training import Trainer
from tests.helpers import layout, stack

ort = pytest.importorskip('onnxruntime')
pytest.importorskip('jax2onnx')
# jax2onnx's GroupNorm plugin reads Variable.value, which Flax deprecates.
pytestmark = pytest.mark.filterwarnings('ignore::DeprecationWarning:jax2onnx')

TINY = 'tiny'
ROOT = pathlib.Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / 'examples' / 'onnx_infer.py'
# Runs a script as __main__ and fails if anything imported JAX along the way.
NO_JAX = '''
import runpy, sys
sys.argv = sys.argv[1:]
try:
  runpy.run_path(sys.argv[0], run_name='__main__')
finally:
  assert 'jax' not in sys.modules, 'the script imported JAX'
'''
CUBE, FLAT = 0, 2
TOLERANCE = 1e-4


def _example():
  spec = importlib.util.spec_from_file_location('onnx_infer', EXAMPLE)
  module = importlib.util.module_from_spec(spec)
  spec.loader.exec_module(module)
  return module


def _workdir(config, workdir, saved=None):
  """(trainer, workdir, params): a work directory as mvcoba-train leaves it, its checkpoint
  holding freshly initialised parameters: training would compile for minutes, and export reads
  only these. `saved`: the config as config.json and the checkpoint hold it (default: all of
  `config`)."""
  trainer = Trainer(config)
  like = jax.eval_shape(trainer.init, jax.random.PRNGKey(config.seed))
  params = trainer.init_params(jax.random.PRNGKey(7))
  state = jax.tree.map(lambda s: jnp.zeros(s.shape, s.dtype), like).replace(params=params)
  saved = to_dict(config) if saved is None else saved
  (workdir / 'config.json').write_text(json.dumps(saved, indent=1))
  Checkpoints(workdir).save(8, state, {'config': saved, 'iteration': 4})
  return trainer, workdir, params


def test_run_saved_before_a_config_field_existed_still_loads(tmp_path):
  """config.json and the checkpoint of a run older than scene.press_force both lack it: both take
  its default, the policy loads, and the warning names the field."""
  config = resolve(TINY)
  saved = to_dict(config)
  del saved['scene']['press_force']
  _workdir(config, tmp_path, saved)
  with pytest.warns(UserWarning, match='scene.press_force=5.0'):
    loaded, _, step = policy.load(tmp_path)
  assert loaded == config and step == 8


@pytest.fixture(scope='module')
def run(tmp_path_factory):
  return _workdir(resolve(TINY), tmp_path_factory.mktemp('run'))


@pytest.fixture(scope='module')
def exported(run, tmp_path_factory):
  _, workdir, _ = run
  paths = export.export(workdir, tmp_path_factory.mktemp('export'))
  session = ort.InferenceSession(str(paths['onnx']), providers=['CPUExecutionProvider'])
  return paths, json.loads(paths['model_json'].read_text()), session


@pytest.fixture(scope='module')
def states(run):
  """name -> (color (1, V, R, R, 3), depth (1, V, R, R)): random, and rendered from a layout."""
  task = run[0].task
  env = task.env
  side = perception.grid_size(task.perception, env.config.scene)
  views = len(env.config.scene.cameras)
  kc, kd = jax.random.split(jax.random.PRNGKey(3))
  random = (jax.random.uniform(kc, (1, views, side, side, 3)),
            0.1 * jax.random.uniform(kd, (1, views, side, side)))
  place = jax.jit(jax.vmap(env.place))  # as tests/test_perception.py: its compiled programs
  look = jax.jit(task.observe)
  obs = look(place(stack([layout(env, [(CUBE, -0.06, 0.04, 0.4), (FLAT, 0.05, -0.03, 0.0)])])))
  return {'random': random, 'rendered': (obs.color, obs.depth)}


@pytest.fixture(scope='module')
def parity(run, exported, states):
  """name -> (JAX Q maps, ONNX Q maps) of each state."""
  trainer, _, params = run
  forward = jax.jit(lambda c, d: nnx.merge(trainer.graphdef, params)(c, d))
  session = exported[2]
  return {name: (np.asarray(forward(c, d)), onnx_outputs(session, c, d, True)['q'])
          for name, (c, d) in states.items()}


def onnx_outputs(session, color, depth, changed: bool) -> dict:
  """Every output of an exported graph on one state, by name."""
  names = [o.name for o in session.get_outputs()]
  return dict(zip(names, session.run(names, {'color': np.asarray(color),
                                             'depth': np.asarray(depth),
                                             'changed': np.array([changed])})))


def jax_action(q, changed, depth, trainer):
  """Greedy action and world point the way the training step picks and executes them."""
  action = agent.greedy_actions(jnp.asarray(q), jnp.array([changed]), trainer.method)
  world = trainer.task.to_world(action, depth)
  return {**{k: int(getattr(action, k)[0]) for k in ('primitive', 'rotation', 'row', 'col')},
          **{k: float(getattr(world, k)[0]) for k in ('x', 'y', 'z')}}


def test_params_npz_round_trips_the_checkpoint(run, exported):
  _, _, params = run
  paths, model, _ = exported
  want = policy.flat_params(nnx.merge(run[0].graphdef, params))
  with np.load(paths['params']) as saved:
    assert sorted(saved.files) == sorted(want) == sorted(model['params']['arrays'])
    for name, array in want.items():
      np.testing.assert_array_equal(saved[name], array, err_msg=name)
      assert model['params']['arrays'][name] == {'shape': list(array.shape),
                                                 'dtype': str(array.dtype)}
  assert len(want) == len(jax.tree.leaves(params))


def test_model_json_describes_frame_rotations_and_rule(exported):
  model = exported[1]
  assert model['heightmap']['grid_size'] == 56 and model['heightmap']['views_used'] == [0, 1]
  assert model['rotations']['num_rotations'] == 16
  np.testing.assert_allclose(model['rotations']['angles_rad'][4], np.pi / 2)
  assert model['action_rule']['name'] == 'change'
  assert model['onnx']['outputs'][0]['shape'] == [1, 2, 16, 56, 56]


@pytest.mark.parametrize('name', ['random', 'rendered'])
def test_onnx_matches_jax_forward_and_action(name, run, exported, parity, states):
  """The graph's Q maps match JAX's, and its action (the rule and argmax, inside the graph) is
  the one the training step's greedy rule picks, after a change and after none."""
  q_jax, q_onnx = parity[name]
  assert q_onnx.shape == q_jax.shape
  diff = float(np.abs(q_onnx - q_jax).max())
  assert diff < TOLERANCE, f'{name}: max |ONNX - JAX| = {diff:.2e}'
  for changed in (False, True):
    want = jax_action(q_jax, changed, states[name][1], run[0])
    got = onnx_outputs(exported[2], *states[name], changed)
    assert list(got['action'][0]) == [want[k] for k in ('primitive', 'rotation', 'row', 'col')]
    assert got['action'].dtype == np.int32 and got['action'][0][0] == int(changed)
    assert abs(float(got['value'][0]) - float(q_jax.reshape(2, -1)[int(changed)].max())) < 1e-4


def test_example_script_prints_the_jax_action_without_jax(run, exported, parity, states,
                                                          tmp_path):
  paths, _, _ = exported
  color, depth = (np.asarray(a[0]) for a in states['rendered'])
  state_path = tmp_path / 'state.npz'
  np.savez(state_path, color=color, depth=depth)
  for changed in (0, 1):
    done = subprocess.run(
        [sys.executable, '-c', NO_JAX,
         str(EXAMPLE), '--model', str(paths['onnx'].parent), '--state', str(state_path),
         '--changed', str(changed)],
        capture_output=True, text=True, cwd=tmp_path, check=False)
    assert done.returncode == 0, done.stderr
    got = json.loads(done.stdout.strip().splitlines()[-1])
    want = jax_action(parity['rendered'][0], bool(changed), states['rendered'][1], run[0])
    for k in ('primitive', 'rotation', 'row', 'col'):
      assert got[k] == want[k], (k, got, want)
    for k in ('x', 'y', 'z'):
      assert abs(got[k] - want[k]) < 1e-6, (k, got, want)
    assert got['primitive_name'] == ('grasp' if changed else 'push')


def test_a_state_saved_by_mvcoba_viz_runs_through_the_onnx_example(run, exported, tmp_path):
  """The docs' two commands end to end: `mvcoba-viz --save-state` writes the heightmaps of a
  settled case and the example picks from them, without JAX, the action JAX picks."""
  trainer, _, params = run
  case = tmp_path / 'case.scn'
  case.write_text('cube red -0.06 0.04 20\nflat_box blue 0.05 -0.03 0\n')
  state = tmp_path / 'state.npz'
  argv = [str(case), '--settle', '--config', TINY, '--out', str(tmp_path / 'viz'),
          '--save-state', str(state)]
  assert viz_cli.main(argv) == 0
  with np.load(state) as saved:
    color, depth = saved['color'], saved['depth']
  assert color.shape == (2, 56, 56, 3) and depth.shape == (2, 56, 56)
  assert 0.04 < depth.max() < 0.06  # the cube's top, seen by both views
  with pytest.raises(SystemExit):  # an existing file is not overwritten
    viz_cli.main(argv)
  done = subprocess.run([sys.executable, '-c', NO_JAX, str(EXAMPLE), '--model',
                         str(exported[0]['onnx'].parent), '--state', str(state)],
                        capture_output=True, text=True, cwd=tmp_path, check=False)
  assert done.returncode == 0, done.stderr
  got = json.loads(done.stdout.strip().splitlines()[-1])
  q = nnx.merge(trainer.graphdef, params)(jnp.asarray(color[None]), jnp.asarray(depth[None]))
  want = jax_action(np.asarray(q), True, jnp.asarray(depth[None]), trainer)
  assert [got[k] for k in ('primitive', 'rotation', 'row', 'col')] == [
      want[k] for k in ('primitive', 'rotation', 'row', 'col')]


@pytest.mark.parametrize('method, overrides', [
    ('mvp', []), ('cpg', []), ('mvcoba', ['network.pad_to_diagonal=true']),
    ('mvcoba_2fcn', ['network.shared_stages=1', 'network.pad_to_diagonal=true']),
    ('mvcoba', ['network.suppress=true', 'network.push_room=0.15']), ('grasp_only', [])])
def test_other_networks_export_round_trip_with_onnx_parity(method, overrides, tmp_path):
  """MVP (four viewpoints fused in the graph), CPG and MV-COBA with `network.suppress` and
  `push_room` (an output more: the suppressed scores its rule compares), a network padded to the diagonal, one
  that turns its features and grasp-only (every rule of methods.py) export like the others: the
  folder loads back as the same policy, and ONNX matches JAX on every output, the action its
  rule picks inside the graph included."""
  (tmp_path / 'run').mkdir()
  trainer, workdir, _ = _workdir(resolve(TINY, [f'network.method={method}', *overrides]),
                                 tmp_path / 'run')
  paths = export.export(workdir, tmp_path / 'export')
  model_json = json.loads(paths['model_json'].read_text())
  config, model, step = policy.load(paths['params'].parent)
  assert config == trainer.config and step == 8
  views = len(config.scene.cameras)
  assert model_json['heightmap']['num_views'] == views == (4 if method == 'mvp' else 2)
  side = perception.grid_size(config.perception, config.scene)
  kc, kd = jax.random.split(jax.random.PRNGKey(5))
  color = jax.random.uniform(kc, (1, views, side, side, 3))
  depth = 0.1 * jax.random.uniform(kd, (1, views, side, side)) ** 4
  q = jax.jit(lambda c, d: model(c, d))(color, depth)
  maps = agent.Decision.of(trainer.method, config).maps(q, depth)
  session = ort.InferenceSession(str(paths['onnx']), providers=['CPUExecutionProvider'])
  names = [o['name'] for o in model_json['onnx']['outputs']]
  suppress = method == 'cpg' or config.network.suppress
  assert names == ['q', *(['score'] if suppress else []), 'action', 'value']
  assert [i['name'] for i in model_json['onnx']['inputs']] == ['color', 'depth', 'changed']
  for changed in (False, True):
    got = onnx_outputs(session, color, depth, changed)
    assert list(got) == names
    assert float(np.abs(got['q'] - np.asarray(q)).max()) < TOLERANCE
    np.testing.assert_allclose(got[model_json['action_rule']['maps']], np.asarray(maps),
                               rtol=1e-5, atol=TOLERANCE)
    want, score = agent.Decision.of(trainer.method, config).act(q, depth, jnp.array([changed]))
    assert list(got['action'][0]) == [int(getattr(want, k)[0])
                                      for k in ('primitive', 'rotation', 'row', 'col')]
    assert abs(float(got['value'][0]) - float(score[0])) < 1e-4


def test_a_policy_that_fills_unseen_cells_acts_alike_in_jax_and_deploy(tmp_path):
  """MV-COBA trained with suppression, a push after a second failed grasp and unseen cells
  filled from the other view, exported: with one camera blind to half the table, deploy (numpy
  fill, ONNX scores, its rule) takes the JAX policy's action, after a change and after none;
  without `seen` the JAX policy refuses."""
  from mvcoba_jax.deploy import OnnxPolicy, calibration_from_dict
  from mvcoba_jax.sim.contract import filled
  from mvcoba_jax.sim import cameras
  (tmp_path / 'run').mkdir()
  trainer, workdir, _ = _workdir(resolve(TINY, ['network.suppress=true',
                                                'perception.fill_unseen=true',
                                                'perception.failed_grasp_changes=false',
                                                'perception.failed_grasp_retries=1']),
                                 tmp_path / 'run')
  folder = export.export(workdir, tmp_path / 'export')['onnx'].parent
  jax_policy, onnx = policy.load(folder), OnnxPolicy(folder)
  assert onnx.spec.fill_unseen and not onnx.spec.failed_grasp_changes
  assert onnx.spec.failed_grasp_retries == 1
  config = jax_policy.config
  side = perception.grid_size(config.perception, config.scene)
  rng = np.random.default_rng(2)
  depth = np.zeros((2, side, side), np.float32)
  depth[:, 10:20, 12:22], depth[:, 30:40, 25:33] = 0.05, 0.03
  color = np.where(depth[..., None] > 0, rng.random((2, side, side, 3)), 0.2).astype(np.float32)
  seen = np.ones((2, side, side), bool)
  seen[0, :, side // 2:] = False  # camera 0 blind to half the table
  depth[0][~seen[0]], color[0][~seen[0]] = 0.0, 0.0
  cal = calibration_from_dict(cameras.calibration(trainer.task.env,
                                                   trainer.config.perception.heightmap_resolution))
  filled_color, filled_depth = filled(color, depth, seen)
  assert (filled_depth[0] == depth[1]).all()  # camera 1 saw all: camera 0 takes its heights
  for changed in (True, False):
    want = jax_policy.act(color, depth, changed, seen=seen)
    got = onnx.act(color, depth, seen, changed, cal)
    # The same primitive at the best score of the same maps; a near tie in the little trained
    # network's maps may pick another cell of that score.
    assert got.primitive == want.primitive == ('grasp' if changed else 'push')
    assert abs(got.q - want.q) < 1e-4, (got, want)
    jax_maps = agent.Decision.of(jax_policy.network.method, config).maps(
        jnp.asarray(jax_policy.q_maps(filled_color, filled_depth))[None],
        jnp.asarray(filled_depth)[None])
    k, r, c = got.rotation, got.row, got.col
    prim = 1 if changed else 0
    assert abs(float(jax_maps[0, prim, k, r, c]) - want.q) < 1e-4
  with pytest.raises(policy.PolicyError, match='seen is needed'):
    jax_policy.act(color, depth, True)


def test_the_rule_is_one_decision_that_every_actor_reads(run, states, monkeypatch, tmp_path):
  """A toy setting of the action rule written in one place, `agent.Decision.maps` (every score at
  rotation 1, cell (3, 5) raised by 100): `Policy.act`, the evaluation's greedy actor and the
  exported graph all take that cell, as the training step explores through the same object."""
  from mvcoba_jax.evaluation.protocols import FROZEN
  from mvcoba_jax.evaluation.sources import Source
  real = agent.Decision.maps
  monkeypatch.setattr(agent.Decision, 'maps', lambda self, q, depth: real(self, q, depth).at[
      :, :, 1, 3, 5].add(100.0))
  trainer, workdir, _ = run
  color, depth = states['rendered']
  loaded = policy.load(workdir)
  config, model, _ = loaded
  action = loaded.act(np.asarray(color[0]), np.asarray(depth[0]), True)
  assert (action.rotation, action.row, action.col) == (1, 3, 5)
  obs = perception.Observation(color=color, depth=depth, seen=depth >= 0)
  actor = Source(model.method, config, model).actor(config, FROZEN)
  chosen, _ = actor.act(None, obs, jnp.array([True]), jnp.ones(1, bool), None, None)
  assert (int(chosen.rotation[0]), int(chosen.row[0]), int(chosen.col[0])) == (1, 3, 5)
  session = ort.InferenceSession(str(export.export(workdir, tmp_path / 'toy')['onnx']),
                                 providers=['CPUExecutionProvider'])
  assert list(onnx_outputs(session, color, depth, True)['action'][0][1:]) == [1, 3, 5]
  assert isinstance(trainer.decision, agent.Decision)


def test_export_folder_loads_back_as_the_same_policy(run, exported, parity, states):
  """What mvcoba-eval --checkpoint does with an exported folder: same config, step and Q maps."""
  trainer, _, _ = run
  config, model, step = policy.load(exported[0]['params'].parent)
  assert config == trainer.config and step == 8
  c, d = states['rendered']
  np.testing.assert_allclose(np.asarray(jax.jit(lambda c, d: model(c, d))(c, d)),
                             parity['rendered'][0], atol=1e-6)


def test_an_export_is_never_replaced_unasked(run, exported, tmp_path, capsys):
  """mvcoba-export into a folder that holds an export is refused before anything is written,
  and replaces it whole with --overwrite."""
  from mvcoba_jax.cli import export as export_cli
  folder = tmp_path / 'shipped'
  shutil.copytree(exported[0]['params'].parent, folder)
  (folder / 'model.json').write_text('{"kept": true}')
  args = ['--checkpoint', str(run[1]), '--out', str(folder)]
  assert export_cli.main(args) == 2
  assert 'holds results of an earlier run' in capsys.readouterr().err
  assert (folder / 'model.json').read_text() == '{"kept": true}'
  assert export_cli.main([*args, '--overwrite']) == 0
  assert json.loads((folder / 'model.json').read_text())['source']['checkpoint_step'] == 8
  assert sorted(p.name for p in folder.iterdir()) == ['.lock', 'model.json', 'model.onnx',
                                                       'params.npz']
  assert not list(tmp_path.glob('.shipped.*'))  # no staging folder left


def test_an_export_its_readers_would_refuse_is_not_written(run, tmp_path, monkeypatch):
  """model.json is read back as the deploy path reads it before anything is written: a field
  that reader refuses (here primitives numbered against the graph) fails the export in one line."""
  real = export.model_file_of
  monkeypatch.setattr(export, 'model_file_of', lambda config, method, step: dataclasses.replace(
      real(config, method, step), push=1, grasp=0))
  with pytest.raises(policy.PolicyError, match='its export would be refused by its readers .*'
                                               'primitives push 1, grasp 0'):
    export.export(run[1], tmp_path / 'out')
  assert not (tmp_path / 'out').exists()


def test_an_export_that_ends_while_another_converts_is_not_replaced(run, tmp_path, monkeypatch):
  """Two exports into one new folder at once: the one that finds the other's export there when
  it comes to write (after its own check and conversion) is refused, and the other's stays."""
  folder, real_load, others = tmp_path / 'new', export.load, []

  def another_export_ends_meanwhile(workdir):
    if not others:  # the other process, ending between this one's first check and its write
      others.append(workdir)
      export.export(workdir, folder)
    return real_load(workdir)

  monkeypatch.setattr(export, 'load', another_export_ends_meanwhile)
  with pytest.raises(policy.PolicyError, match='holds results of an earlier run'):
    export.export(run[1], folder)
  written = json.loads((folder / 'model.json').read_text())
  assert others and written['source']['checkpoint_step'] == 8


def test_replacing_an_export_leaves_the_old_or_the_new_never_a_mix(run, exported, tmp_path,
                                                                   monkeypatch):
  """--overwrite writes the new export beside the old and swaps the two at once: a write that
  fails (a full disk) keeps the old export whole and a file of the user's beside it; kills at
  three moments of a real `mvcoba-export` leave the old export or the new one, each whole."""
  folder = tmp_path / 'shipped'
  shutil.copytree(exported[0]['params'].parent, folder)
  (folder / 'model.json').write_text('{"old": true}')
  (folder / 'notes.txt').write_text('mine')
  files = lambda: {p.name: p.read_bytes() for p in folder.iterdir() if p.name != '.lock'}
  old = files()
  real_write = open

  def full_disk(path, mode='r', *args, **kwargs):
    if 'w' in mode and str(path).endswith('model.onnx'):
      raise OSError(28, 'No space left on device')
    return real_write(path, mode, *args, **kwargs)

  monkeypatch.setattr('builtins.open', full_disk)
  with pytest.raises(policy.PolicyError, match='No space left on device.*what it held is kept'):
    export.export(run[1], folder, overwrite=True)
  monkeypatch.undo()
  assert files() == old
  assert not list(tmp_path.glob('.shipped.*'))
  export.export(run[1], folder, overwrite=True)
  new = files()
  assert new['notes.txt'] == b'mine' and new['model.json'] != old['model.json']
  (folder / 'model.json').write_bytes(old['model.json'])  # old again, for the kills
  old = files()
  command = [sys.executable, '-m', 'mvcoba_jax.cli.export', '--checkpoint', str(run[1]),
             '--out', str(folder), '--overwrite']
  for delay in (4.0, 8.0, 12.0):
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(delay)
    process.kill()
    process.wait()
    now = files()
    assert now == old or (
        now.keys() == new.keys() and now['params.npz'] == new['params.npz']
        and json.loads(now['model.json'])['source'] == json.loads(new['model.json'])['source']
        and len(now['model.onnx']) == len(new['model.onnx'])), (delay, sorted(now))


def test_export_folder_of_another_network_is_a_clear_error(exported, tmp_path):
  folder = tmp_path / 'other'
  shutil.copytree(exported[0]['params'].parent, folder)
  with np.load(folder / 'params.npz') as saved:
    arrays = {n: saved[n] for n in saved.files}
  first, last = sorted(arrays)[0], sorted(arrays)[-1]
  arrays[first] = arrays[first][..., :1]
  del arrays[last]
  np.savez(folder / 'params.npz', **arrays)
  with pytest.raises(policy.PolicyError, match='does not fit') as error:
    policy.load(folder)
  message = str(error.value)
  assert str(folder / 'params.npz') in message
  assert f'{first}: shape' in message and f'{last}: missing' in message


@pytest.mark.parametrize('folder', sorted(p for p in (ROOT / 'pretrained').iterdir() if p.is_dir()),
                         ids=lambda p: p.name)
def test_shipped_pretrained_policy_fits_the_current_network(folder):
  """A change of the network that would leave a shipped policy unloadable fails here: train and
  export it again (README, Pretrained policy)."""
  config, model, step = policy.load(folder)
  assert config.network.method == folder.name and step > 0
  assert all(np.isfinite(a).all() for a in policy.flat_params(model).values())


def test_every_shipped_policy_evaluates(tmp_path):
  """What docs/usage.md runs on pretrained/*/: each shipped policy loads without a warning and
  acts in a case (one run, a few actions, every policy in one call)."""
  folders = sorted(str(p) for p in (ROOT / 'pretrained').iterdir() if p.is_dir())
  case = ROOT / 'mvcoba_jax' / 'suites' / 'dev-ordered' / 'dev-ordered-00.scn'
  with warnings.catch_warnings():
    warnings.simplefilter('error', UserWarning)
    report = mvcoba_jax.evaluate(folders, [str(case)], runs=1, max_actions=3, out=tmp_path,
                                 progress=False)
  rows = next(iter(report.values()))
  assert len(rows) == len(folders)
  assert all(sum(r['actions'] for r in row['runs']['dev-ordered-00']) > 0 for row in rows.values())


def test_shipped_example_state_is_an_input_of_the_shipped_policy():
  """pretrained/example-state.npz is what the docs run examples/onnx_infer.py on."""
  from mvcoba_jax.deploy import model_file
  spec = model_file.read(ROOT / 'pretrained' / 'mvcoba')
  color, depth = _example().load_state(ROOT / 'pretrained' / 'example-state.npz', spec)
  assert 0.0 <= color.min() and color.max() <= 1.0 and 0.02 < depth.max() < 0.2


def test_a_loaded_policy_acts_as_evaluation_does():
  """`load_policy(...).act` on the shipped example state takes the action the evaluation's
  greedy policy takes (the method's rule over the argmax rotation and cell), in both branches of
  MV-COBA's rule, with the cell's centre and surface height in the workspace frame."""
  from mvcoba_jax import perception
  from mvcoba_jax.evaluation.protocols import FROZEN
  from mvcoba_jax.evaluation.sources import Source
  loaded = policy.load(ROOT / 'pretrained' / 'mvcoba')
  config, model, step = loaded
  state = np.load(ROOT / 'pretrained' / 'example-state.npz')
  obs = perception.Observation(color=jnp.asarray(state['color'])[None],
                               depth=jnp.asarray(state['depth'])[None],
                               seen=jnp.asarray(state['seen'])[None])
  greedy = Source(config.network.method, config, model).actor(config, FROZEN)
  for changed in (True, False):
    chosen, _ = greedy.act(None, obs, jnp.asarray([changed]), jnp.ones(1, bool), None, None)
    decision = loaded.act(state['color'], state['depth'], changed, seen=state['seen'])
    assert (decision.primitive, decision.rotation, decision.row, decision.col) == (
        ('push', 'grasp')[int(chosen.primitive[0])], int(chosen.rotation[0]),
        int(chosen.row[0]), int(chosen.col[0]))
    res, half = config.perception.heightmap_resolution, config.scene.workspace_half
    x, _, z = decision.position
    assert x == pytest.approx(-half + (decision.col + 0.5) * res, abs=1e-6)
    assert z == pytest.approx(state['depth'][:, decision.row, decision.col].max())
  assert loaded.act(state['color'], state['depth'], True, seen=state['seen']).primitive == 'grasp'


def test_missing_work_directory_is_a_clear_error(tmp_path):
  missing = tmp_path / 'nowhere'
  with pytest.raises(policy.PolicyError, match='nowhere'):
    export.export(missing, tmp_path / 'out')
  command = pathlib.Path(sys.executable).parent / 'mvcoba-export'  # the installed entry point
  done = subprocess.run([str(command), '--checkpoint', str(missing),
                         '--out', str(tmp_path / 'out')], capture_output=True, text=True,
                        cwd=ROOT, check=False)
  assert done.returncode == 2
  assert str(missing) in done.stderr and 'Traceback' not in done.stderr
  assert not (tmp_path / 'out').exists()


def test_work_directory_without_checkpoints_is_a_clear_error(run, tmp_path, capsys):
  workdir = tmp_path / 'fresh'
  (workdir / 'checkpoints').mkdir(parents=True)
  shutil.copy(run[1] / 'config.json', workdir / 'config.json')
  with pytest.raises(policy.PolicyError, match='no checkpoint'):
    policy.load(workdir)
  assert export_cli.main(['--checkpoint', str(workdir), '--out', str(tmp_path / 'out')]) == 2
  assert str(workdir / 'checkpoints') in capsys.readouterr().err


def test_checkpoint_of_another_network_shape_is_a_clear_error(run, tmp_path, capsys):
  workdir = tmp_path / 'other'
  shutil.copytree(run[1], workdir)
  config = dataclasses.replace(run[0].config, network=dataclasses.replace(
      run[0].config.network, features=(8, 32)))
  (workdir / 'config.json').write_text(json.dumps(to_dict(config)))
  with pytest.raises(policy.PolicyError, match='network.features'):
    policy.load(workdir)
  assert export_cli.main(['--checkpoint', str(workdir), '--out', str(tmp_path / 'out')]) == 2
  err = capsys.readouterr().err
  assert 'network.features' in err and str(workdir / 'config.json') in err


def test_config_json_from_before_a_field_existed_warns_with_the_default_it_takes(run, tmp_path):
  workdir = tmp_path / 'old'
  shutil.copytree(run[1], workdir)
  saved = json.loads((workdir / 'config.json').read_text())
  assert defaulted(saved, from_dict(saved)) == {}
  del saved['scene']['contact_timeconst']
  (workdir / 'config.json').write_text(json.dumps(saved))
  with pytest.warns(UserWarning, match=r'config\.json lacks .* scene\.contact_timeconst=0\.008'):
    config, _, _ = policy.load(workdir)
  assert config == run[0].config


def test_saved_configs_with_retired_fields_load(run):
  """The training failure limit became env.max_failures, shared with evaluation: older saved
  configs that still hold the old field load, and take the shared limit."""
  saved = to_dict(run[0].config)
  saved['train']['max_consecutive_failures'] = 10
  del saved['env']['max_failures']
  config = from_dict(saved)
  assert config.env.max_failures == 5 and config.train == run[0].config.train


def test_config_round_trips_through_json(run):
  config = run[0].config
  assert from_dict(json.loads(json.dumps(to_dict(config)))) == config
  with pytest.raises(ConfigError, match='network: unknown keys width'):
    from_dict({'network': {'width': 3}})
