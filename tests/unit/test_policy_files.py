"""Damaged or mismatched policy files (a training checkpoint, an exported folder) fail with one
PolicyError naming the file and what is wrong, never a traceback from NumPy, Orbax or JAX."""
import json
import pathlib
import re
import shutil

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from flax import nnx

from mvcoba_jax import export, policy
from mvcoba_jax.cli import eval as eval_cli
from mvcoba_jax.config import resolve, to_dict
from mvcoba_jax.learner.checkpoint import Checkpoints
from mvcoba_jax.learner.training import Trainer


@pytest.fixture(scope='module')
def saved(tmp_path_factory):
  """(work directory with one checkpoint, exported folder, trainer, initial state)."""
  config = resolve('tiny')
  trainer = Trainer(config)
  like = jax.eval_shape(trainer.init, jax.random.PRNGKey(config.seed))
  params = trainer.init_params(jax.random.PRNGKey(7))
  state = jax.tree.map(lambda s: jnp.zeros(s.shape, s.dtype), like).replace(params=params)
  workdir = tmp_path_factory.mktemp('run')
  (workdir / 'config.json').write_text(json.dumps(to_dict(config)))
  Checkpoints(workdir).save(8, state, {'config': to_dict(config), 'iteration': 4})
  folder = tmp_path_factory.mktemp('exported')
  flat = policy.flat_params(nnx.merge(trainer.graphdef, params))
  np.savez(folder / 'params.npz', **flat)
  described = export.describe(config, trainer.method, flat, 8, workdir)
  (folder / 'model.json').write_text(json.dumps(described))
  return workdir, folder, state


def _copy(source, tmp_path):
  target = tmp_path / source.name
  shutil.copytree(source, target)
  return target


def _arrays(folder):
  with np.load(folder / 'params.npz') as saved:
    return {n: saved[n] for n in saved.files}


def test_intact_files_load(saved):
  workdir, folder, _ = saved
  assert policy.load(workdir)[2] == 8 and policy.load(folder)[2] == 8


def _refused(path, *says):
  with pytest.raises(policy.PolicyError) as error:
    policy.load(path)
  message = str(error.value)
  assert all(s in message for s in says), message
  return message


@pytest.mark.parametrize('damage', ['truncated', 'empty', 'bit-flipped'])
def test_damaged_params_npz(saved, tmp_path, damage):
  folder = _copy(saved[1], tmp_path)
  data = (folder / 'params.npz').read_bytes()
  data = {'truncated': data[:len(data) // 2], 'empty': b'',
          'bit-flipped': data[:len(data) // 2] + bytes([data[len(data) // 2] ^ 0x40])
          + data[len(data) // 2 + 1:]}[damage]
  (folder / 'params.npz').write_bytes(data)
  _refused(folder, str(folder / 'params.npz'))


def test_non_finite_and_wrong_dtype_params(saved, tmp_path):
  folder = _copy(saved[1], tmp_path)
  arrays = _arrays(folder)
  first, second = sorted(arrays)[:2]
  arrays[first] = np.full_like(arrays[first], np.nan)
  arrays[second] = arrays[second].astype(np.float64)
  np.savez(folder / 'params.npz', **arrays)
  _refused(folder, f'{first}: holds NaN', f'{second}: dtype float64')
  arrays = _arrays(_copy(saved[1], tmp_path / 'large'))
  arrays[first] = np.full_like(arrays[first], 3e38)
  np.savez(folder / 'params.npz', **arrays)
  _refused(folder, f'{first}: holds values beyond')


@pytest.mark.parametrize('edit, says', [
    (lambda d: d['config']['train'].update(batch_size='eight'), "train.batch_size='eight'"),
    (lambda d: d['config']['perception'].update(heightmap_resolution=0.003),
     'config.perception.heightmap_resolution is not heightmap.resolution_m'),
    (lambda d: d['config']['perception'].update(heightmap_resolution=0.003)
     or d['heightmap'].update(resolution_m=0.003, grid_size=149), 'must tile'),
    (lambda d: d['source'].update(checkpoint_step='x'),
     "source.checkpoint_step 'x': a whole number expected"),
    (lambda d: d['source'].update(checkpoint_step=float('inf')), 'Infinity is not a number'),
    (lambda d: d['source'].update(checkpoint_step=-3), 'source.checkpoint_step -3 outside'),
    (lambda d: d.update(format='other/1'), "format 'other/1'"),
    (lambda d: d['source'].update(checkpoint_step=10 ** 30), 'checkpoint_step 1000000'),
    (lambda d: d['config']['env'].update(num_rotations=8),
     'rotations.num_rotations 16 (its config gives 8)'),
])
def test_bad_model_json(saved, tmp_path, edit, says):
  folder = _copy(saved[1], tmp_path)
  described = json.loads((folder / 'model.json').read_text())
  edit(described)
  (folder / 'model.json').write_text(json.dumps(described))
  _refused(folder, str(folder / 'model.json'), says)
  (folder / 'model.json').write_bytes(b'{"format": \xff')
  _refused(folder, str(folder / 'model.json'))


def test_damaged_checkpoint(saved, tmp_path):
  workdir = _copy(saved[0], tmp_path)
  for f in (workdir / 'checkpoints' / '8' / 'state').rglob('*'):
    if f.is_file() and f.stat().st_size:
      f.write_bytes(f.read_bytes()[:f.stat().st_size // 2])
  _refused(workdir, str(workdir / 'checkpoints' / '8'))
  workdir = _copy(saved[0], tmp_path / 'meta')
  for f in (workdir / 'checkpoints' / '8' / 'meta').rglob('*'):
    if f.is_file():
      f.write_text('{not json')
  _refused(workdir, str(workdir / 'checkpoints' / '8'))


def test_empty_step_folder_is_ignored_or_named(saved, tmp_path):
  workdir = _copy(saved[0], tmp_path)
  (workdir / 'checkpoints' / '16').mkdir()
  try:
    assert policy.load(workdir)[2] == 8
  except policy.PolicyError as e:
    assert str(workdir / 'checkpoints' / '16') in str(e)


def test_non_finite_checkpoint_parameters(saved, tmp_path):
  workdir = _copy(saved[0], tmp_path)
  shutil.rmtree(workdir / 'checkpoints')
  state = saved[2]
  state = state.replace(params=jax.tree.map(lambda p: jnp.full_like(p, jnp.inf), state.params))
  config = resolve('tiny')
  Checkpoints(workdir).save(8, state, {'config': to_dict(config), 'iteration': 4})
  _refused(workdir, 'NaN or infinite')


def test_eval_cli_names_the_damaged_file_in_one_line(saved, tmp_path, capsys):
  folder = _copy(saved[1], tmp_path)
  (folder / 'params.npz').write_bytes(b'')
  assert eval_cli.main(['--checkpoint', str(folder), '--suite', 'occluded', '--out',
                        str(tmp_path / 'out')]) == 2
  err = capsys.readouterr().err
  assert err.startswith('error: ') and str(folder / 'params.npz') in err
  assert 'Traceback' not in err and not (tmp_path / 'out').exists()


def test_checkpoint_of_another_state_structure_is_refused(tmp_path):
  """Leaves are saved by tree path: a state whose fields changed cannot be filled from a
  checkpoint with another field's values of the same shape."""
  from mvcoba_jax.learner.checkpoint import CheckpointError
  config = resolve('tiny')
  saved = {'replay': {'size': jnp.int32(3)}, 'actions': jnp.int32(8)}
  Checkpoints(tmp_path).save(8, saved, {'config': to_dict(config)})
  state, _ = Checkpoints(tmp_path).restore(saved, config)
  assert int(state['actions']) == 8 and int(state['replay']['size']) == 3
  renamed = {'replay': {'cursor': jnp.int32(0)}, 'actions': jnp.int32(0)}
  with pytest.raises(CheckpointError, match='cannot be read'):
    Checkpoints(tmp_path).restore(renamed, config)


def test_fuzzed_model_json_loads_or_is_refused_naming_it(saved, tmp_path):
  """Generated bad model.json files (fixed seed: a value swapped for an odd one at a random place
  of the source or config, a key dropped): each loads or is one PolicyError naming the file."""
  import random
  _, folder, _ = saved
  rng = random.Random(1)
  odd = [None, 'x', -1, 2 ** 70, 1e300, float('inf'), True, [], {}, [[1]]]
  base = json.loads((folder / 'model.json').read_text())
  refused = 0
  for i in range(40):
    described = json.loads(json.dumps(base))
    section = rng.choice([described, described['source'], described['config']['train'],
                          described['config']['env'], described['config']['network']])
    key = rng.choice(sorted(section))
    if rng.random() < 0.2:
      del section[key]
    else:
      section[key] = rng.choice(odd)
    target = tmp_path / f'm{i}'
    shutil.copytree(folder, target)
    (target / 'model.json').write_text(json.dumps(described))
    try:
      policy.load(target)
    except policy.PolicyError as e:
      refused += 1
      assert str(target / 'model.json') in str(e) or str(target / 'params.npz') in str(e), str(e)
  assert refused > 20


def test_model_json_is_written_and_read_through_one_schema(saved, tmp_path):
  """What `export.describe` wrote reads back (`deploy.model_file.read`) as the fields it was
  written from, every one; a heightmap unit or floor other than the one this runtime's
  heightmaps use is refused naming the field."""
  from mvcoba_jax.deploy import DeployError, model_file
  _, folder, _ = saved
  config = resolve('tiny')
  written = export.model_file_of(config, Trainer(config).method, 8)
  assert model_file.read(folder) == written
  assert written.height_unit_m == 1e-5 and written.below_table_m == -0.005
  for dotted, value in (('height_unit_m', 1e-3), ('below_table_m', -0.05)):
    target = _copy(folder, tmp_path / dotted)
    described = json.loads((target / 'model.json').read_text())
    described['heightmap'][dotted] = value
    (target / 'model.json').write_text(json.dumps(described))
    with pytest.raises(DeployError, match=f'heightmap.{dotted} {value!r}: this runtime'):
      model_file.read(target)


def test_a_tabletop_takes_the_scene_and_episode_alone():
  """`Tabletop` is built from `config.tabletop`; handed the whole config it refuses, before
  building anything, so nothing in the simulator reads perception or training settings."""
  from mvcoba_jax.sim.tabletop import Tabletop
  with pytest.raises(TypeError, match='TabletopConfig'):
    Tabletop(resolve('tiny'))


def _constant_graph(folder, inputs, outputs):
  """A model.onnx whose outputs are constants: (name, onnx type, shape) for each input and
  output, so an export's graph can be given any names, types and shapes."""
  import onnx  # noqa: PLC0415 (a dev extra)
  from onnx import TensorProto, helper  # noqa: PLC0415

  types = {'float': TensorProto.FLOAT, 'bool': TensorProto.BOOL, 'int32': TensorProto.INT32}
  values = {'float': np.float32, 'bool': np.bool_, 'int32': np.int32}
  nodes = [helper.make_node('Constant', [], [name], value=onnx.numpy_helper.from_array(
      np.zeros(shape, values[kind]))) for name, kind, shape in outputs]
  graph = helper.make_graph(
      nodes, 'constant', [helper.make_tensor_value_info(n, types[k], s) for n, k, s in inputs],
      [helper.make_tensor_value_info(n, types[k], s) for n, k, s in outputs])
  onnx.save(helper.make_model(graph, opset_imports=[helper.make_opsetid('', 17)]),
            folder / 'model.onnx')


EXPORT_INPUTS = [('color', 'float', [1, 2, 112, 112, 3]), ('depth', 'float', [1, 2, 112, 112]),
                 ('changed', 'bool', [1])]
EXPORT_OUTPUTS = [('action', 'int32', [1, 4]), ('value', 'float', [1])]


@pytest.mark.parametrize('inputs, outputs, says', [
    (EXPORT_INPUTS, EXPORT_OUTPUTS, None),
    (EXPORT_INPUTS, [('action', 'int32', [1, 4]), ('score', 'float', [1])],
     "the graph's outputs are action, score; an export's are action, value and more"),
    ([*EXPORT_INPUTS, ('extra', 'float', [1])], EXPORT_OUTPUTS,
     "the graph's inputs are changed, color, depth, extra"),
    ([('colour', 'float', [1, 2, 112, 112, 3]), *EXPORT_INPUTS[1:]], EXPORT_OUTPUTS,
     "the graph's inputs are changed, colour, depth"),
    ([EXPORT_INPUTS[0], ('depth', 'float', [1, 2, 96, 96]), EXPORT_INPUTS[2]], EXPORT_OUTPUTS,
     r'input depth is tensor\(float\) \[1, 2, 96, 96\]; model.json \(2 views, a 112 x 112 grid\)'),
    ([*EXPORT_INPUTS[:2], ('changed', 'float', [1])], EXPORT_OUTPUTS,
     r'input changed is tensor\(float\) \[1\]; .* needs tensor\(bool\) \[1\]'),
    (EXPORT_INPUTS, [('action', 'float', [1, 4]), EXPORT_OUTPUTS[1]],
     r'output action is tensor\(float\)'),
])
def test_an_exported_graph_is_checked_against_model_json(tmp_path, inputs, outputs, says):
  """Opening an export refuses, in one line naming the file, a graph whose inputs or outputs
  (names, element types, shapes) are not the ones model.json's policy needs."""
  from mvcoba_jax.deploy import DeployError, OnnxPolicy  # noqa: PLC0415
  shutil.copy('pretrained/mvcoba/model.json', tmp_path / 'model.json')
  _constant_graph(tmp_path, inputs, outputs)
  if says is None:
    policy_ = OnnxPolicy(tmp_path)
    zeros = np.zeros((2, 112, 112), np.float32)
    assert policy_.choose(zeros[..., None].repeat(3, -1), zeros, True) == (0, 0, 0, 0, 0.0)
    return
  with pytest.raises(DeployError, match=f'{tmp_path / "model.onnx"}: {says}'):
    OnnxPolicy(tmp_path)


def test_model_json_with_primitives_swapped_is_refused(tmp_path):
  """A model.json that numbers grasp 0 would relabel the graph's grasps as pushes."""
  from mvcoba_jax.deploy import DeployError, model_file  # noqa: PLC0415
  described = json.loads(pathlib.Path('pretrained/mvcoba/model.json').read_text())
  described['primitives'] = {'push': 1, 'grasp': 0}
  (tmp_path / 'model.json').write_text(json.dumps(described))
  with pytest.raises(DeployError, match='primitives push 1, grasp 0: the graph\'s action numbers '
                                        'push 0 and grasp 1'):
    model_file.read(tmp_path)


def test_every_setting_an_export_carries_has_one_range(tmp_path):
  """The settings model.json carries to a robot (`sim.contract.RANGES`): a config refuses a
  value just outside each range, naming it, and model.json's reader refuses the same values, so
  an evaluation cannot run a push length that an export of it would refuse."""
  from mvcoba_jax.config import ConfigError
  from mvcoba_jax.deploy import DeployError, model_file
  from mvcoba_jax.sim.contract import RANGES
  for key, (low, high) in RANGES.items():
    step = 1 if isinstance(low, int) else max(1e-9, low * 1e-3)
    for outside in (low - step, high + step):
      with pytest.raises(ConfigError, match=f'{re.escape(key)}=.*allowed range'):
        resolve('default', [f'{key}={outside!r}'])
  described = json.loads(pathlib.Path('pretrained/mvcoba/model.json').read_text())
  for section, key in (('env', 'push_length'), ('perception', 'change_area'),
                       ('perception', 'failed_grasp_retries')):
    low = RANGES[f'{section}.{key}'][0]
    edited = json.loads(json.dumps(described))
    edited['config'][section][key] = low - (1 if isinstance(low, int) else low * 1e-3)
    (tmp_path / 'model.json').write_text(json.dumps(edited))
    with pytest.raises(DeployError, match=f'config.{section}.{key}'):
      model_file.read(tmp_path)


def test_the_deploy_policys_other_arguments_are_typed(tmp_path):
  """`other_gripper` is a plain yes or no (a string does not wave the gripper check through) and
  `act` takes a Calibration, each refused in one line otherwise."""
  from mvcoba_jax.deploy import DeployError, OnnxPolicy  # noqa: PLC0415
  shutil.copy('pretrained/mvcoba/model.json', tmp_path / 'model.json')
  _constant_graph(tmp_path, EXPORT_INPUTS, EXPORT_OUTPUTS)
  with pytest.raises(DeployError, match="other_gripper='no': True or False"):
    OnnxPolicy(tmp_path, gripper='robotiq_2f85', other_gripper='no')
  assert OnnxPolicy(tmp_path, gripper='robotiq_2f85', other_gripper=True).gripper['name'] == 'rg2'
  zeros = np.zeros((2, 112, 112), np.float32)
  with pytest.raises(DeployError, match=r'calibration=\{\}: a deploy.Calibration expected'):
    OnnxPolicy(tmp_path).act(zeros[..., None].repeat(3, -1), zeros, zeros > 0, True, {})


def test_fuzzed_deploy_arguments_are_refused_in_one_line_or_accepted(tmp_path):
  """The deploy API's yes-or-no and count arguments (fixed seed): `changed`, `grasped` and
  `failures` of odd types and values are each refused in one DeployError line, or taken
  when they are what the API documents (a bool, numpy's included; a count of 0 or more)."""
  import random

  from mvcoba_jax.deploy import DeployError, OnnxPolicy  # noqa: PLC0415
  shutil.copy('pretrained/mvcoba/model.json', tmp_path / 'model.json')
  _constant_graph(tmp_path, EXPORT_INPUTS, EXPORT_OUTPUTS)
  onnx = OnnxPolicy(tmp_path)
  rng = random.Random(0)
  odd = [True, False, np.True_, np.False_, None, 0, 1, -1, 1.5, '1', 'no', [], [True],
         np.asarray(True), np.int64(2), 2 ** 70, float('nan')]
  depth = np.zeros((2, 112, 112), np.float32)
  frame = (depth, depth > 0)
  valid = lambda flag: isinstance(flag, (bool, np.bool_))
  for _ in range(200):
    grasped, failed = rng.choice(odd), rng.choice(odd)
    count = isinstance(failed, (int, np.integer)) and not valid(failed) and failed >= 0
    try:
      onnx.changed(frame, frame, grasped=grasped, failures=failed)
      assert (grasped is None or valid(grasped)) and count, (grasped, failed)
    except DeployError as e:
      assert '\n' not in str(e) and not ((grasped is None or valid(grasped)) and count), (
          grasped, failed, str(e))
    changed = rng.choice(odd)
    with pytest.raises(DeployError) as e:  # a real flag gets as far as the calibration
      onnx.act(depth[..., None].repeat(3, -1), depth, depth > 0, changed, None)
    assert ('True or False' in str(e.value)) != valid(changed), (changed, str(e.value))
