"""Configs are checked when built: presets, `--set` overrides and saved dicts go through the same
field and relation checks, and a bad value is refused with the key and what it allows."""
import dataclasses
import pathlib
import random
import re
import typing

import pytest

from mvcoba_jax.config import (
  PRESETS,
  Config,
  ConfigError,
  defaulted,
  evaluated,
  from_dict,
  resolve,
  to_dict,
)
from mvcoba_jax.deploy import model_file
from mvcoba_jax.sim import grippers, procedural


@pytest.mark.parametrize('preset', PRESETS)
def test_presets_are_valid(preset):
  assert isinstance(resolve(preset), Config)


@pytest.mark.parametrize('assignment, says', [
    ('scene.timestep=0', 'scene.timestep=0.0: allowed range [0.0001, 0.02]'),
    ('network.stem_patch=0', 'network.stem_patch=0: allowed range [1, 16]'),
    ('network.groups=3', 'network.groups=3 must divide'),
    ('network.features=', 'network.features: at least one stage'),
    ('perception.heightmap_resolution=0', 'perception.heightmap_resolution=0.0: allowed'),
    ('perception.heightmap_resolution=0.003', 'must tile the workspace'),
    ('num_envs=0', 'num_envs=0: allowed range [1, 65536]'),
    ('env.num_rotations=0', 'env.num_rotations=0: allowed range [1, 64]'),
    ('train.checkpoint_every=0', 'train.checkpoint_every=0: allowed range'),
    ('train.learning_rate=nan', "train.learning_rate='nan': expected a finite number"),
    ('train.learning_rate=1e300', 'train.learning_rate=1e+300: allowed range (0, 1]'),
    ('train.replay_capacity=5000000', 'GiB of replay; the limit is 16 GiB'),
    ('seed=18446744073709551616', 'seed=18446744073709551616: allowed range'),
    ('num_envs=١', "num_envs='١': expected an integer"),
    ('env.num_objects=99', 'env.num_objects=99 exceeds the 12 object slots of scene.pool'),
    ('scene.backend=jax', "scene.backend='jax': allowed values are auto, native, mjx, warp"),
    ('scene.pool=cube', 'expected shape:count'),
    ('scene.pool=cube:1,cube:2', 'expected distinct shapes'),
    ('scene.pool=lego:2', "scene.pool: unknown shape 'lego'; known: prism, arch"),
    ('scene.contact_timeconst=0.001', 'below 2 x scene.timestep'),
    ('scene.noslip_iterations=-1', 'scene.noslip_iterations=-1: allowed range [0, 1000]'),
    ('scene.cameras=1', 'cannot be set from the command line'),
    ('perception.change_min=0.5', 'perception.change_min=0.5 must be below'),
    ('network.method=nope', "network.method='nope': allowed values are"),
    ('train.epsilon_end=0.9', 'must not exceed train.epsilon_start'),
    ('num_envs=4096', 'GiB of feature maps per acting forward'),
    ('env.drop=pile', "env.drop='pile': allowed values are spread, heap"),
    ('env.heap_half=0.3', 'env.heap_half=0.3 must not exceed scene.workspace_half'),
    ('env.occluded_share=1.5', 'env.occluded_share=1.5: allowed range [0, 1]'),
    ('env.packed_share=-0.1', 'env.packed_share=-0.1: allowed range [0, 1]'),
    ('train.future_max=all', "train.future_max='all': allowed values are rule, both"),
    ('train.no_change_push_reward=-2', 'train.no_change_push_reward=-2.0: allowed range'),
    ('env.descend_speed=1e-300', 'env.approach_height / env.descend_speed = 8e+298 s'),
    ('env.push_speed=0.00005', 'env.push_length / env.push_speed = 1e+03 s of simulated motion'),
    ('train.batch_size=2000', 'train.batch_size=2000 exceeds train.replay_capacity=1024'),
])
def test_bad_override_is_refused_naming_the_key(assignment, says):
  with pytest.raises(ConfigError) as error:
    resolve('default', [assignment])
  assert says in str(error.value)


def test_overrides_apply_in_any_order():
  """Relations are checked once every override is in."""
  config = resolve('default', ['scene.pool=cube:2', 'env.num_objects=2'])
  assert config.scene.num_slots == 2 and config.env.num_objects == 2


def test_occluders_can_be_set():
  config = resolve('default', ['scene.occluders=0.01:0.1:0.1,0.02:0.05:0.05'])
  assert config.scene.occluders == ((0.01, 0.1, 0.1), (0.02, 0.05, 0.05))


def test_saved_config_with_wrong_types_is_refused_naming_the_key():
  saved = to_dict(resolve('tiny'))
  saved['train']['batch_size'] = 'eight'
  with pytest.raises(ConfigError, match=r"train\.batch_size='eight': expected an integer"):
    from_dict(saved)
  saved = to_dict(resolve('tiny'))
  saved['network']['features'] = 16
  with pytest.raises(ConfigError, match=r'config\.network\.features=16: expected a list'):
    from_dict(saved)
  with pytest.raises(ConfigError, match='expected an object of SceneConfig fields'):
    from_dict({**to_dict(resolve('tiny')), 'scene': [1, 2]})


def _leaf_keys(node, prefix=''):
  hints = typing.get_type_hints(type(node))
  for field in dataclasses.fields(node):
    value = getattr(node, field.name)
    if dataclasses.is_dataclass(value):
      yield from _leaf_keys(value, f'{prefix}{field.name}.')
    else:
      yield f'{prefix}{field.name}', hints[field.name]


NASTY = ('nan', 'inf', '-inf', '1e300', '-1e300', '1e-300', '0', '-1', '1', '2', '0.5', '-0.5',
         '18446744073709551616', '2**64', '١٢', '', ' ', 'abc', '1,2', '1,2,3', 'cube:3',
         'cube:3,disk:1', 'true', 'false', '0x10', '1_000', '1e3', '3.', '.5', '+7', '\u2028',
         'é', '0.01:0.1:0.1', '::', ',', 'None', '[1, 2]', '1' * 400, 'auto', 'mjx', 'small')


def test_fuzzed_overrides_are_accepted_or_refused_naming_the_key():
  """300 overrides from a fixed seed: each is a valid config or a ConfigError that names its
  key; nothing else escapes."""
  rng = random.Random(0)
  keys = list(_leaf_keys(Config()))
  outcomes = {'accepted': 0, 'refused': 0}
  for _ in range(300):
    key, _ = rng.choice(keys)
    text = rng.choice(NASTY) if rng.random() < 0.8 else repr(rng.uniform(-1e3, 1e3))
    try:
      resolve('tiny', [f'{key}={text}'])
      outcomes['accepted'] += 1
    except ConfigError as e:
      assert key.split('.')[-1] in str(e) or 'workspace' in str(e), (key, text, str(e))
      outcomes['refused'] += 1
  assert outcomes['accepted'] > 10 and outcomes['refused'] > 100, outcomes


def test_saved_config_without_a_newer_field_gets_what_its_run_used():
  """Runs saved before train.target existed bootstrapped from the target network."""
  saved = to_dict(resolve('tiny', ['train.target=acting']))
  del saved['train']['target']
  config = from_dict(saved)
  assert config.train.target == 'network' and defaulted(saved, config) == {}


def test_saved_config_without_the_recipe_fields_keeps_the_paper_text_recipe():
  """Runs saved before the recipe fields existed trained with the paper's text: they load with
  those values, without a warning, whatever the presets now choose."""
  saved = to_dict(resolve('authors', ['network.pad_to_diagonal=true', 'network.shared_stages=2']))
  for name in ('failed_grasp_reward', 'no_change_push_reward', 'bootstrap_no_change',
               'future_max', 'grasp_symmetry', 'fresh_in_batch', 'quarter_turns'):
    del saved['train'][name]
  del saved['env']['drop'], saved['env']['occluded_share'], saved['env']['packed_share']
  del saved['network']['pad_to_diagonal'], saved['network']['shared_stages']
  config = from_dict(saved)
  assert config.train == resolve('paper_text').train and config.env.drop == 'spread'
  assert config.env.occluded_share == 0 and config.env.packed_share == 0
  assert not config.network.pad_to_diagonal
  assert config.network.shared_stages == 0
  assert defaulted(saved, config) == {}


def test_noslip_pass_is_refused_on_mjx_which_would_run_without_it():
  assert resolve('default', ['scene.noslip_iterations=3']).scene.noslip_iterations == 3
  with pytest.raises(ConfigError, match='scene.noslip_iterations=3 needs the native or warp '
                                        'backend: MJX has no noslip pass'):
    resolve('default', ['scene.backend=mjx', 'scene.noslip_iterations=3'])


def test_recipe_settings_that_do_not_fit_together_are_refused():
  with pytest.raises(ConfigError, match='grasp_symmetry needs an even env.num_rotations'):
    resolve('default', ['train.grasp_symmetry=true', 'env.num_rotations=7'])
  with pytest.raises(ConfigError, match='quarter_turns needs env.num_rotations divisible by 4'):
    resolve('default', ['train.quarter_turns=true', 'env.num_rotations=6'])
  import dataclasses

  from mvcoba_jax.config import validate
  config = resolve('tiny', ['env.occluded_share=0.5'])
  with pytest.raises(ConfigError, match='needs an occluder slot'):
    validate(dataclasses.replace(config, scene=dataclasses.replace(config.scene, occluders=())))


def test_evaluation_overrides_change_physics_not_what_training_fixed():
  """`mvcoba-eval --set` applies to every trained policy's config: its physics and episode may
  change, its network, perception, rotations and workspace may not."""
  trained = resolve('tiny')
  assert evaluated(trained, ['scene.press_force=60']).scene.press_force == 60.0
  for key, value in (('network.trunk', 'densenet121'), ('perception.change_min', '0.02'),
                     ('env.num_rotations', '8'), ('scene.workspace_half', '0.2')):
    with pytest.raises(ConfigError, match=f'--set {key}: fixed by the trained policy'):
      evaluated(trained, [f'{key}={value}'])


def test_evaluation_may_change_the_rule_after_a_failed_grasp_not_what_the_network_reads():
  """The `ACTING_RULE` fields pick the primitive after a failed grasp, which the network does
  not read: a trained policy acts under other values at evaluation; retries without the push
  after a failed grasp would change nothing and are refused, in training as at evaluation."""
  trained = resolve('tiny', ['perception.failed_grasp_changes=false'])
  acting = evaluated(trained, ['perception.failed_grasp_retries=2'])
  assert acting.perception.failed_grasp_retries == 2 and acting.network == trained.network
  assert evaluated(resolve('tiny'), ['perception.failed_grasp_changes=false']
                   ).perception.failed_grasp_changes is False
  with pytest.raises(ConfigError, match='failed_grasp_retries=1 needs '
                                        'perception.failed_grasp_changes=false'):
    evaluated(resolve('tiny'), ['perception.failed_grasp_retries=1'])
  with pytest.raises(ConfigError, match='failed_grasp_retries=1 needs'):
    resolve('tiny', ['perception.failed_grasp_retries=1'])
  with pytest.raises(ConfigError, match=r'failed_grasp_retries=101: allowed range \[0, 100\]'):
    evaluated(trained, ['perception.failed_grasp_retries=101'])


def test_preset_files_that_are_not_python_or_whose_get_config_raises_are_one_line(tmp_path):
  from mvcoba_jax.config import load_preset
  (tmp_path / 'preset.json').write_text('{"seed": 1}')
  with pytest.raises(ConfigError, match=r'preset.json: a preset file is Python \(.py\)'):
    load_preset(tmp_path / 'preset.json')
  (tmp_path / 'raises.py').write_text('def get_config():\n  return 1 / 0\n')
  with pytest.raises(ConfigError, match='get_config.. raised ZeroDivisionError: division by zero'):
    load_preset(tmp_path / 'raises.py')


def test_replay_ratio_sets_the_updates_per_lockstep_action():
  """Sampled replayed transitions per new one stay at the ratio as the batch of tabletops grows."""
  for envs, updates in ((8, 1), (32, 4), (64, 8), (256, 32)):
    config = resolve('default', [f'num_envs={envs}', 'train.replay_ratio=1'])
    assert config.updates_per_step == updates
    assert updates * config.train.batch_size / envs == 1
  assert resolve('default', ['num_envs=64']).updates_per_step == 1  # off: one update a step
  assert resolve('default', ['num_envs=2', 'train.replay_ratio=0.5']).updates_per_step == 1


def test_a_run_trains_whole_calls_of_every_tabletop_k_times():
  """What the progress bar counts to and a resume checks against: total_actions rounded up to
  whole calls of num_envs x steps_per_iteration."""
  for total, trained in ((6000, 6016), (6016, 6016), (1, 32)):
    config = resolve('default', [f'train.total_actions={total}'])
    assert (config.actions_per_call, config.actions_trained) == (32, trained)
  assert resolve('default', ['num_envs=3', 'train.steps_per_iteration=1',
                             'train.total_actions=10']).actions_trained == 12


def test_a_preset_that_exits_is_a_config_error(tmp_path):
  preset = tmp_path / 'quits.py'
  preset.write_text('import sys\nsys.exit(3)\n')
  with pytest.raises(ConfigError, match='quits.py: SystemExit: 3'):
    resolve(str(preset))
  preset.write_text('import sys\ndef get_config():\n  sys.exit(4)\n')
  with pytest.raises(ConfigError, match='get_config\\(\\) raised SystemExit: 4'):
    resolve(str(preset))


def test_saved_config_without_the_winning_policy_fields_keeps_the_papers_rule():
  """Runs saved before the screen's fields existed acted by the paper's rule on each view's own
  heightmap: they load so, without a warning."""
  trained = resolve('tiny', ['network.suppress=true', 'perception.fill_unseen=true',
                             'perception.failed_grasp_changes=false'])
  saved = to_dict(trained)
  del saved['network']['suppress']
  del saved['perception']['fill_unseen'], saved['perception']['failed_grasp_changes']
  config = from_dict(saved)
  assert not config.network.suppress and not config.perception.fill_unseen
  assert config.perception.failed_grasp_changes and defaulted(saved, config) == {}


def test_warp_without_a_cuda_device_is_refused_unless_forced(tmp_path, monkeypatch, capsys):
  """The gpu preset on a machine where Warp finds no CUDA device (every CI machine): training,
  evaluation, the demo and the pictures are refused in one line naming the CPU's preset, before
  anything compiles or is written; the environment variable runs it all the same; native MuJoCo
  is never refused."""
  import warp

  from mvcoba_jax import suites
  from mvcoba_jax.cli import demo as demo_cli
  from mvcoba_jax.cli import eval as eval_cli
  from mvcoba_jax.cli import viz as viz_cli

  from mvcoba_jax.learner.train import TrainError, train
  from mvcoba_jax.sim import physics
  if warp.is_cuda_available():
    pytest.skip('Warp finds a CUDA device here')
  monkeypatch.delenv(physics.FORCE_WARP_CPU, raising=False)
  gpu = resolve('gpu')
  assert '--config default' in physics.device_problem(gpu.scene)
  assert physics.device_problem(resolve('default').scene) is None
  with pytest.raises(TrainError, match='Warp finds no CUDA device here'):
    train(resolve('tiny', ['scene.backend=warp']), tmp_path / 'run')
  assert not (tmp_path / 'run').exists()
  case = sorted(pathlib.Path(suites.__file__).parent.joinpath('isolated').iterdir())[0]
  for main, argv in ((eval_cli.main, ['--baseline', 'heuristic', '--suite', str(case), '--out',
                                      str(tmp_path / 'eval')]),
                     (viz_cli.main, [str(case), '--out', str(tmp_path / 'viz')]),
                     (demo_cli.main, [])):
    try:
      code = main([*argv, '--config', 'gpu'])
    except SystemExit as e:  # argparse's error
      code = e.code
    assert code == 2 and 'Warp finds no CUDA device here' in capsys.readouterr().err, main
  assert not (tmp_path / 'eval').exists() and not (tmp_path / 'viz').exists()
  monkeypatch.setenv(physics.FORCE_WARP_CPU, '1')
  assert physics.device_problem(gpu.scene) is None


def test_contact_caps_a_settled_drop_cannot_fit_are_refused_on_mjx_and_warp():
  """`scene.max_contact_points=1` on Warp dropped objects through the table: refused on the two
  backends that cap contacts; native MuJoCo has no caps, so the fields mean nothing there."""
  for backend in ('mjx', 'warp'):
    with pytest.raises(ConfigError, match='needs at least 40 contact points'):
      resolve('default', [f'scene.backend={backend}', 'scene.max_contact_points=1'])
    with pytest.raises(ConfigError, match=r"objects' 14 convex parts on the table \(.*arch: 3"):
      resolve('default', [f'scene.backend={backend}', 'scene.max_geom_pairs=13'])
    assert resolve('default', [f'scene.backend={backend}']).scene.max_contact_points == 120
  assert resolve('default', ['scene.backend=native', 'scene.max_contact_points=1'])
  mug = str(procedural.OBJECTS / 'everyday' / 'mug')  # 12 parts, named inside the package
  with pytest.raises(ConfigError, match="package:sim/objects/everyday/mug: 12 parts"):
    resolve('default', ['scene.backend=mjx', f'scene.pool=cube:2,{mug}:1', 'env.num_objects=3',
                        'scene.max_geom_pairs=12'])


def test_the_gripper_is_one_description_set_by_preset_or_field():
  """`scene.gripper=NAME` takes a preset whole; a field is set alone; a saved config from before
  the gripper was a group (its friction the scene's) reads as the RG2 with that friction."""
  config = resolve('default', ['scene.gripper=robotiq_2f85', 'scene.gripper.finger_force=50'])
  assert config.scene.gripper == dataclasses.replace(grippers.ROBOTIQ_2F85, finger_force=50.0)
  for assignment, says in (
      ('scene.gripper=lego', "scene.gripper='lego': unknown gripper; presets: rg2, robotiq_2f85"),
      ('scene.gripper.max_opening=0.015', 'must exceed twice scene.gripper.finger_thickness'),
      ('scene.gripper.finger_length=0.02', 'env.grasp_depth=0.03 must be below'),
      ('scene.gripper.finger_width=0', 'scene.gripper.finger_width=0.0: allowed range')):
    with pytest.raises(ConfigError, match=re.escape(says)):
      resolve('default', [assignment])
  old = to_dict(resolve('default'))
  del old['scene']['gripper']
  old['scene']['finger_friction'] = 1.2
  assert from_dict(old).scene.gripper == dataclasses.replace(grippers.RG2, finger_friction=1.2)
  assert defaulted(old, from_dict(old)) == {}
  assert dataclasses.asdict(grippers.RG2) == {**model_file.RG2, 'palm': tuple(model_file.RG2[
      'palm'])}
