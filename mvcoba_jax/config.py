"""Configuration: frozen dataclasses, presets, `key=value` overrides.

A preset is a module of `mvcoba_jax.presets` (`default`, `paper`, `tiny`, named by `--config`) or a
Python file given by path; either defines `get_config() -> Config`. Overrides use dotted paths
(`env.num_objects=5`, `scene.pool=cube:3,disk:1`) and are parsed by the field's type, so a typo
or a bad value fails with a message that names the key.
"""
from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import json
import math
import pathlib
import re
import typing

from mvcoba_jax import methods
from mvcoba_jax.sim.config import (
  Between,
  CameraConfig,
  ConfigError,
  EnvConfig,
  Error,
  SceneConfig,
  check,
)

__all__ = ['CameraConfig', 'Config', 'ConfigError', 'EnvConfig', 'Error', 'NetworkConfig',
           'PerceptionConfig', 'SceneConfig', 'TrainConfig']


TRUNKS = ('small', 'densenet121')
TARGETS = ('network', 'acting')  # train.target
FUTURE_MAX = ('rule', 'both')  # train.future_max


@dataclasses.dataclass(frozen=True)
class PerceptionConfig:
  """Heightmaps and change observation."""
  heightmap_resolution: float = 0.004  # m per cell: 112 x 112 (the paper: 0.002 -> 224 x 224)
  # Change is observed when more cells than `change_area` / resolution^2 changed height by
  # between `change_min` and `change_max`: VPG's 300 cells at 2 mm, the same area at any grid.
  change_area: float = 300 * 0.002 ** 2
  change_min: float = 0.01
  change_max: float = 0.3

  def __post_init__(self):
    check(self, 'perception.', {'heightmap_resolution': Between(0.0005, 0.05),
                                'change_area': Between(0, 1, low_open=True),
                                'change_min': Between(0, 1), 'change_max': Between(0, 1)})


@dataclasses.dataclass(frozen=True)
class NetworkConfig:
  """The Q-network. `method` picks the architecture and the action rule."""
  method: str = 'mvcoba'  # a method of mvcoba_jax/methods.py
  trunk: str = 'small'  # 'small' (CPU-sized, from scratch) or 'densenet121' (GPU-sized)
  stem_patch: int = 4  # the stem turns patch x patch cells into one feature vector
  features: tuple[int, ...] = (32, 64, 64)  # channels of the trunk stages (small trunk)
  groups: int = 8  # GroupNorm groups
  # Pad the heightmaps to their diagonal before turning them, as the authors' code does, so no
  # turn cuts a corner off; costs about 2x the forward. (Their other input change, a 2x zoom,
  # is `stem_patch` halved: a patch over a nearest-neighbour zoom is a patch half the size.)
  pad_to_diagonal: bool = False
  # Stages run once per state before the turn (small trunk): 0 turns the heightmaps and runs the
  # whole FCN per rotation; 1 runs the streams once and turns their feature maps; n > 1 also the
  # trunk's first n - 1 blocks. At least one block runs per rotation, or every turn would score
  # alike. Each FCN's maps are then turned back at the stem's resolution and upsampled.
  shared_stages: int = 0

  def __post_init__(self):
    check(self, 'network.', {'trunk': TRUNKS, 'stem_patch': Between(1, 16),
                             'shared_stages': Between(0, 16),
                             'features': Between(1, 4096), 'groups': Between(1, 512)})
    if not self.features:
      raise ConfigError('network.features: at least one stage')
    if self.shared_stages and self.trunk != 'small':
      raise ConfigError(f'network.shared_stages={self.shared_stages} needs network.trunk=small')
    if self.shared_stages >= len(self.features):
      raise ConfigError(f'network.shared_stages={self.shared_stages}: at most '
                        f'{len(self.features) - 1} with network.features={self.features} (one '
                        'block at least runs per rotation)')


@dataclasses.dataclass(frozen=True)
class TrainConfig:
  """Q-learning."""
  total_actions: int = 3000  # counted over all environments
  steps_per_iteration: int = 4  # lockstep actions per compiled call (lax.scan length)
  learning_rate: float = 1e-4
  momentum: float = 0.9
  weight_decay: float = 2e-5
  gamma: float = 0.5
  huber_delta: float = 1.0
  epsilon_start: float = 0.5
  epsilon_end: float = 0.1
  epsilon_decay_actions: int = 800  # linear decay over this many actions (~25 min on 2 CPU cores)
  explore_min_height: float = 0.01  # random actions go to heightmap cells above this (m)
  replay_capacity: int = 1024  # transitions kept on the device
  batch_size: int = 8  # transitions per SGD update
  # Replayed transitions sampled per new transition. 0: one update per lockstep action, so the
  # ratio is batch_size / num_envs and falls as the batch of tabletops grows; > 0: as many
  # updates per lockstep action as keep it (`updates_per_step`), the same at any num_envs.
  replay_ratio: float = 0.0
  priority_exponent: float = 0.6  # sampling weight |TD error|^alpha (0: uniform)
  target_update_period: int = 50  # SGD updates between target-network copies
  # Where max Q(s') of the bootstrap target comes from: 'acting', the online network's acting
  # forward at s', computed anyway one step later and stored with the transition; 'network' (the
  # paper's), the target network run on each sampled s' at update time. 'acting' trains 1.7x as
  # many actions/s at B=8 and learned as well over 3 seeds (docs/results/learner-throughput.md).
  target: str = 'acting'
  # The learning recipe (the `authors` preset holds the MV-COBA authors' code's values; these
  # defaults are the paper's text): rewards of a failed grasp that changed the scene and of a
  # push that changed nothing; whether an action that changed nothing bootstraps (False: its
  # future is 0, as in VPG's and the authors' code); the future's max over the rule's primitive
  # ('rule') or over both primitives' maps ('both'); every grasp also labelled at its rotation
  # turned half way (a parallel-jaw grasp is the same grasp turned by 180 degrees); each update
  # also trains on the B transitions stored this step, besides `batch_size` replayed ones.
  # Beyond both: `quarter_turns` turns each replayed transition (states and action) by a random
  # multiple of 90 degrees about the heightmap centre, teaching a network whose early stages see
  # the state unturned (`network.shared_stages`) the symmetry that turned heightmaps build in.
  failed_grasp_reward: float = 0.5
  no_change_push_reward: float = 0.0
  bootstrap_no_change: bool = True
  future_max: str = 'rule'
  grasp_symmetry: bool = False
  fresh_in_batch: bool = False
  quarter_turns: bool = False
  checkpoint_every: int = 25  # host iterations between checkpoints
  curve_window: int = 200  # attempts in the sliding window of the training curves

  def __post_init__(self):
    check(self, 'train.', {
        'total_actions': Between(1, 10 ** 9), 'steps_per_iteration': Between(1, 10000),
        'learning_rate': Between(0, 1, low_open=True), 'momentum': Between(0, 0.999),
        'weight_decay': Between(0, 0.1), 'gamma': Between(0, 0.999),
        'huber_delta': Between(0, 100, low_open=True), 'epsilon_start': Between(0, 1),
        'epsilon_end': Between(0, 1), 'epsilon_decay_actions': Between(1, 10 ** 9),
        'explore_min_height': Between(0, 0.4), 'replay_capacity': Between(1, 10 ** 7),
        'batch_size': Between(1, 4096), 'replay_ratio': Between(0, 64),
        'priority_exponent': Between(0, 10),
        'target_update_period': Between(1, 10 ** 9), 'target': TARGETS,
        'checkpoint_every': Between(1, 10 ** 9), 'failed_grasp_reward': Between(-1, 1),
        'no_change_push_reward': Between(-1, 1), 'future_max': FUTURE_MAX,
        'curve_window': Between(1, 10 ** 7)})


@dataclasses.dataclass(frozen=True)
class Config:
  scene: SceneConfig = SceneConfig()
  env: EnvConfig = EnvConfig()
  perception: PerceptionConfig = PerceptionConfig()
  network: NetworkConfig = NetworkConfig()
  train: TrainConfig = TrainConfig()
  num_envs: int = 8
  seed: int = 0

  def __post_init__(self):
    check(self, '', {'num_envs': Between(1, 65536), 'seed': Between(0, 2 ** 31 - 1)})

  @property
  def updates_per_step(self) -> int:
    """SGD updates after each lockstep action: 1, or with `train.replay_ratio` as many batches
    as sample that many replayed transitions per new one (at least 1)."""
    ratio = self.train.replay_ratio
    return 1 if ratio == 0 else max(1, round(ratio * self.num_envs / self.train.batch_size))


MAX_ACTIONS_LIMIT = 10_000  # actions of one evaluation run or greedy check: counters and traces grow with it
REPLAY_LIMIT_BYTES = 16 * 2 ** 30  # a replay above this is refused: no CPU here holds it twice
ACTIVATION_LIMIT_BYTES = 32 * 2 ** 30  # rough size of one acting forward's feature maps
DENSENET_GROWTH = 32  # channels each DenseNet layer adds: GroupNorm's groups must divide it
PHASE_LIMIT_S = 30.0  # simulated seconds of one primitive phase or a reset's settling


def validate(config: Config) -> Config:
  """Raises ConfigError when fields that are each valid do not fit together; returns `config`.

  `resolve` and `from_dict` call it, after every override is in (so overrides can come in any
  order); the fields themselves are checked when each dataclass is built.
  """
  scene, env, net, train = config.scene, config.env, config.network, config.train
  if env.num_objects > scene.num_slots:
    raise ConfigError(f'env.num_objects={env.num_objects} exceeds the {scene.num_slots} object '
                      f'slots of scene.pool; lower it or add slots to scene.pool')
  cells = 2 * scene.workspace_half / config.perception.heightmap_resolution
  side = round(cells)
  if abs(cells - side) > 1e-6 * cells or side < 8 or side > 4096:
    raise ConfigError(
        f'perception.heightmap_resolution={config.perception.heightmap_resolution!r} must tile '
        f'the workspace (2 x scene.workspace_half = {2 * scene.workspace_half:g} m) in a whole '
        f'number of cells between 8 and 4096; it gives {cells:g}')
  if config.perception.change_min >= config.perception.change_max:
    raise ConfigError(f'perception.change_min={config.perception.change_min!r} must be below '
                      f'perception.change_max={config.perception.change_max!r}')
  if train.epsilon_end > train.epsilon_start:
    raise ConfigError(f'train.epsilon_end={train.epsilon_end!r} must not exceed '
                      f'train.epsilon_start={train.epsilon_start!r}')
  widths = (DENSENET_GROWTH,) if net.trunk == 'densenet121' else net.features
  if train.batch_size > train.replay_capacity:
    raise ConfigError(f'train.batch_size={train.batch_size} exceeds train.replay_capacity='
                      f'{train.replay_capacity}: a batch would draw the same transitions again')
  phases = {'env.approach_height / env.descend_speed': env.approach_height / env.descend_speed,
            'env.lift_height / env.lift_speed': env.lift_height / env.lift_speed,
            'env.push_length / env.push_speed': env.push_length / env.push_speed,
            'env.close_time': env.close_time, 'env.hold_time': env.hold_time,
            'env.settle_steps x scene.timestep': env.settle_steps * scene.timestep}
  for name, seconds in phases.items():
    if seconds > PHASE_LIMIT_S:
      raise ConfigError(f'{name} = {seconds:.3g} s of simulated motion; at most '
                        f'{PHASE_LIMIT_S:g} s per phase of a primitive or a reset')
  if train.grasp_symmetry and env.num_rotations % 2:
    raise ConfigError(f'train.grasp_symmetry needs an even env.num_rotations (the grasp turned '
                      f'half way); it is {env.num_rotations}')
  if train.quarter_turns and env.num_rotations % 4:
    raise ConfigError(f'train.quarter_turns needs env.num_rotations divisible by 4 (a quarter '
                      f'turn of the state is a whole number of rotations); it is '
                      f'{env.num_rotations}')
  if env.heap_half > scene.workspace_half:
    raise ConfigError(f'env.heap_half={env.heap_half!r} must not exceed scene.workspace_half='
                      f'{scene.workspace_half!r}')
  if env.occluded_share > 0 and not scene.occluders:
    raise ConfigError(f'env.occluded_share={env.occluded_share!r} needs an occluder slot in '
                      'scene.occluders')
  if any(w % net.groups for w in widths):
    raise ConfigError(f'network.groups={net.groups} must divide every channel count of the '
                      f'{net.trunk} trunk ({", ".join(map(str, widths))}: network.features)')
  if net.method not in methods.names():
    raise ConfigError(f'network.method={net.method!r}: allowed values are '
                      f'{", ".join(methods.names())}')
  views = methods.get(net.method).views
  if max(views) >= len(scene.cameras):
    raise ConfigError(f'network.method={net.method!r} reads camera views {views}; '
                      f'scene.cameras holds {len(scene.cameras)} (choosing the method with '
                      '--method or --set network.method sets the cameras it needs)')
  num_views = len(scene.cameras)
  # Per cell and view, s and s' each: uint8 colour (3 B), float16 depth (2 B), a seen flag (1 B).
  replay = train.replay_capacity * 2 * num_views * side ** 2 * 6
  if replay > REPLAY_LIMIT_BYTES:
    raise ConfigError(f'train.replay_capacity={train.replay_capacity} at {side} x {side} cells '
                      f'and {num_views} views needs {replay / 2 ** 30:.1f} GiB of replay; the '
                      f'limit is {REPLAY_LIMIT_BYTES / 2 ** 30:g} GiB')
  stem = max(side // (4 if net.trunk == 'densenet121' else net.stem_patch), 1)
  acting = (config.num_envs * env.num_rotations * stem ** 2 * max(net.features + (64,)) * 4
            * (len(net.features) + 2))
  if acting > ACTIVATION_LIMIT_BYTES:
    raise ConfigError(f'num_envs={config.num_envs} x env.num_rotations={env.num_rotations} at '
                      f'{side} x {side} cells needs about {acting / 2 ** 30:.0f} GiB of feature '
                      f'maps per acting forward; the limit is '
                      f'{ACTIVATION_LIMIT_BYTES / 2 ** 30:g} GiB')
  return config


PRESETS = ('default', 'paper', 'paper_text', 'authors', 'gpu', 'tiny')  # modules of mvcoba_jax.presets


def load_preset(preset: str | pathlib.Path) -> Config:
  """Config returned by `get_config()` of a preset named in `PRESETS` or of a preset file."""
  if str(preset) in PRESETS:
    module = importlib.import_module(f'mvcoba_jax.presets.{preset}')
  else:
    path = pathlib.Path(preset)
    if not path.is_file():
      raise ConfigError(f'config preset {path}: neither a file nor one of {", ".join(PRESETS)}')
    if path.suffix != '.py':
      raise ConfigError(f'config preset {path}: a preset file is Python (.py) that defines '
                        'get_config()')
    spec = importlib.util.spec_from_file_location(f'mvcoba_preset_{path.stem}', path)
    module = importlib.util.module_from_spec(spec)
    try:
      spec.loader.exec_module(module)
    except (Exception, SystemExit) as e:  # a user's Python file: its error is theirs, named
      raise ConfigError(f'config preset {path}: {type(e).__name__}: {str(e)[:200]}') from None
  if not hasattr(module, 'get_config'):
    raise ConfigError(f'config preset {preset} defines no get_config()')
  try:
    config = module.get_config()
  except ConfigError:
    raise
  except (Exception, SystemExit) as e:  # a user's Python: its error is theirs, named
    raise ConfigError(f'config preset {preset}: get_config() raised {type(e).__name__}: '
                      f'{str(e)[:200]}') from None
  if not isinstance(config, Config):
    raise ConfigError(f'config preset {preset}: get_config() returned {type(config).__name__}, '
                      'not a mvcoba_jax.config.Config')
  return config


_INT = re.compile(r'[+-]?[0-9]{1,20}')
_FLOAT = re.compile(r'[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]{1,3})?')


def _parse(text: str, tp, key: str):
  """`text` as a value of type `tp`; ASCII numbers only, nan and inf refused. Sequences are
  comma-separated; the pool is `shape:count,...`, the occluders `hx:hy:hz,...`."""
  def fail(why: str):
    return ConfigError(f'override {key}={text!r}: {why}')

  if tp is bool:
    if text.lower() not in ('true', 'false', '1', '0'):
      raise fail('expected true or false')
    return text.lower() in ('true', '1')
  if tp is int:
    if not _INT.fullmatch(text):
      raise fail('expected an integer')
    return int(text)
  if tp is float:
    if not _FLOAT.fullmatch(text) or not math.isfinite(float(text)):
      raise fail('expected a finite number')
    return float(text)
  if tp is str:
    return text
  args = typing.get_args(tp) if typing.get_origin(tp) is tuple else ()
  if args == (tuple[str, int], Ellipsis):  # scene.pool
    items = [item.split(':') for item in text.split(',')]
    if not all(len(item) == 2 and _INT.fullmatch(item[1]) for item in items):
      raise fail('expected shape:count[,shape:count...], e.g. cube:3,disk:1')
    return tuple((name, _parse(n, int, key)) for name, n in items)
  if args == (tuple[float, float, float], Ellipsis):  # scene.occluders
    items = [item.split(':') for item in text.split(',')]
    if not all(len(item) == 3 for item in items):
      raise fail('expected hx:hy:hz[,hx:hy:hz...] (half sizes, m)')
    return tuple(tuple(_parse(v, float, key) for v in item) for item in items)
  if len(args) == 2 and args[1] is Ellipsis and not dataclasses.is_dataclass(args[0]):
    return tuple(_parse(t, args[0], key) for t in text.split(',') if t)
  if args and Ellipsis not in args:
    parts = text.split(',')
    if len(parts) != len(args):
      raise fail(f'expected {len(args)} comma-separated values')
    return tuple(_parse(t, a, key) for t, a in zip(parts, args))
  raise ConfigError(f'override {key}: this field cannot be set from the command line; '
                    'write a preset file')


def override(config, assignment: str):
  """Config with one `dotted.key=value` assignment applied; setting network.method to a method
  that names its cameras (`methods.Method.cameras`) sets scene.cameras to them too."""
  if '=' not in assignment:
    raise ConfigError(f'override {assignment!r} is not of the form key=value')
  key, text = assignment.split('=', 1)
  path = key.strip().split('.')

  def apply(node, names):
    fields = {f.name: f for f in dataclasses.fields(node)}
    if names[0] not in fields:
      raise ConfigError(f'unknown config key {key!r}: {type(node).__name__} has no field '
                        f'{names[0]!r} (fields: {", ".join(fields)})')
    value = getattr(node, names[0])
    if len(names) > 1:
      if not dataclasses.is_dataclass(value):
        raise ConfigError(f'unknown config key {key!r}: {names[0]!r} has no sub-fields')
      return dataclasses.replace(node, **{names[0]: apply(value, names[1:])})
    hints = typing.get_type_hints(type(node))
    if dataclasses.is_dataclass(value):
      raise ConfigError(f'config key {key!r} is a group; set one of its fields')
    return dataclasses.replace(node, **{names[0]: _parse(text.strip(), hints[names[0]], key)})

  config = apply(config, path)
  if path == ['network', 'method'] and config.network.method in methods.names():
    cameras = methods.get(config.network.method).cameras
    if cameras:  # a method that moves its camera brings its poses
      config = dataclasses.replace(config, scene=dataclasses.replace(config.scene, cameras=cameras))
  return config


def resolve(preset: str | pathlib.Path | None, overrides: typing.Sequence[str] = ()) -> Config:
  """The preset (or the default preset) with `overrides` applied in order."""
  if preset is None:
    preset = 'default'
  config = load_preset(preset)
  for assignment in overrides:
    config = override(config, assignment)
  return validate(config)


# What a trained policy's network was built for: no --set of these at evaluation.
FIXED_BY_TRAINING = ('network.', 'perception.', 'env.num_rotations', 'scene.workspace_half')


def evaluated(config: Config, overrides: typing.Sequence[str]) -> Config:
  """A trained policy's config with an evaluation's `--set` overrides (physics, episode), which
  may not touch what training fixed (`FIXED_BY_TRAINING`)."""
  for assignment in overrides:
    key = assignment.split('=', 1)[0].strip()
    if key.startswith(FIXED_BY_TRAINING):
      raise ConfigError(f'--set {key}: fixed by the trained policy\'s network (its network, '
                        'perception, rotations and workspace); it cannot change at evaluation')
    config = override(config, assignment)
  return validate(config)


def flat(tree: dict, prefix: str = '') -> dict:
  """{dotted name: leaf} of a nested dict (a config as `to_dict` gives it)."""
  if not isinstance(tree, dict):
    return {prefix[:-1]: tree}
  return {k: v for name, sub in tree.items() for k, v in flat(sub, f'{prefix}{name}.').items()}


def to_dict(config) -> dict:
  return dataclasses.asdict(config)


def from_dict(data: dict, cls=Config, where: str = 'config'):
  """The frozen `cls` dataclass of a `config.to_dict` dict (as JSON holds it: lists for tuples).

  Missing fields keep their defaults, so older config.json files still load (`defaulted` names
  them); unknown ones fail.
  """
  if not isinstance(data, dict):
    raise ConfigError(f'{where}: expected an object of {cls.__name__} fields, got {data!r:.60}')
  fields = {f.name for f in dataclasses.fields(cls)}
  data = {**LEGACY.get(cls, {}), **{k: v for k, v in data.items() if k not in RETIRED.get(cls, ())}}
  unknown = sorted(set(data) - fields)
  if unknown:
    raise ConfigError(f'{where}: unknown keys {", ".join(unknown)} for {cls.__name__}')
  hints = typing.get_type_hints(cls)
  config = cls(**{k: _value(v, hints[k], f'{where}.{k}') for k, v in data.items()})
  return validate(config) if cls is Config else config


# Fields that saved configs may hold and that no longer exist: dropped when read. The training
# failure limit became `env.max_failures`, shared with evaluation (its default, 5, is the paper's).
RETIRED = {TrainConfig: ('max_consecutive_failures',)}

# Fields added after runs were saved without them, with the value those runs used (which is not
# the current default): a saved config that lacks them gets that value, without a warning.
LEGACY = {TrainConfig: {'target': 'network', 'failed_grasp_reward': 0.5,
                        'no_change_push_reward': 0.0, 'bootstrap_no_change': True,
                        'future_max': 'rule', 'grasp_symmetry': False, 'fresh_in_batch': False,
                        'quarter_turns': False, 'replay_ratio': 0.0},
          EnvConfig: {'drop': 'spread', 'heap_half': 0.125, 'occluded_share': 0.0,
                      'packed_share': 0.0},
          NetworkConfig: {'pad_to_diagonal': False, 'shared_stages': 0}}

# Fields that choose where a run computes, not what it computes: a saved config that lacks them
# (written before they existed) runs on this machine's choice without a warning.
RUNTIME_FIELDS = ('scene.backend', 'scene.native_threads')


def defaulted(data: dict, config, prefix: str = '') -> dict:
  """{dotted name: value} of the fields of `config` (= `from_dict(data)`) that `data` lacks and
  that took their defaults: fields added after `data` was written, maybe not what its run used."""
  found = {}
  for f in dataclasses.fields(config):
    value = getattr(config, f.name)
    if f.name not in data:
      if prefix + f.name not in RUNTIME_FIELDS and f.name not in LEGACY.get(type(config), {}):
        found[prefix + f.name] = value
    elif dataclasses.is_dataclass(value):
      found.update(defaulted(data[f.name], value, f'{prefix}{f.name}.'))
  return found


def trained_as(config: Config) -> dict:
  """What a policy was trained as: `to_dict` without the seed and the fields that choose where
  it ran (`RUNTIME_FIELDS`). Policies that share it differ only in their training seed, which is
  what an interval over seeds may pool."""
  data = to_dict(config)
  del data['seed']
  for name in RUNTIME_FIELDS:
    section, field = name.split('.')
    del data[section][field]
  return json.loads(json.dumps(data))  # as results.json holds it: lists for tuples


def _value(value, tp, where: str):
  if dataclasses.is_dataclass(tp):
    return from_dict(value, tp, where)
  if typing.get_origin(tp) is tuple:
    if not isinstance(value, (list, tuple)):
      raise ConfigError(f'{where}={value!r:.60}: expected a list')
    args = typing.get_args(tp)
    if len(args) == 2 and args[1] is Ellipsis:
      args = (args[0],) * len(value)
    return tuple(_value(v, a, f'{where}[{i}]') for i, (v, a) in enumerate(zip(value, args)))
  return value


def add_arguments(parser) -> None:
  """The `--config` and `--set` options every entry point takes."""
  parser.add_argument('--config', default=None,
                      help=f'preset: {"/".join(PRESETS)} or a preset file (default: default)')
  parser.add_argument('--set', dest='overrides', action='append', default=[],
                      metavar='KEY=VALUE', help='override a config field, e.g. env.num_objects=5')


def from_arguments(args) -> Config:
  return resolve(args.config, args.overrides)
