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
import pathlib
import typing

from mvcoba_jax.sim.config import CameraConfig, ConfigError, EnvConfig, SceneConfig

__all__ = ['CameraConfig', 'Config', 'ConfigError', 'EnvConfig', 'NetworkConfig',
           'PerceptionConfig', 'SceneConfig', 'TrainConfig']


@dataclasses.dataclass(frozen=True)
class PerceptionConfig:
  """Heightmaps and change observation."""
  heightmap_resolution: float = 0.004  # m per cell: 112 x 112 (the paper: 0.002 -> 224 x 224)
  # Change is observed when more cells than `change_area` / resolution^2 changed height by
  # between `change_min` and `change_max`: VPG's 300 cells at 2 mm, the same area at any grid.
  change_area: float = 300 * 0.002 ** 2
  change_min: float = 0.01
  change_max: float = 0.3


@dataclasses.dataclass(frozen=True)
class NetworkConfig:
  """The Q-network. `method` picks the architecture and the action rule."""
  method: str = 'mvcoba'  # a method of mvcoba_jax/methods.py
  trunk: str = 'small'  # 'small' (CPU-sized, from scratch) or 'densenet121' (GPU-sized)
  stem_patch: int = 4  # the stem turns patch x patch cells into one feature vector
  features: tuple[int, ...] = (32, 64, 64)  # channels of the trunk stages (small trunk)
  groups: int = 8  # GroupNorm groups


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
  batch_size: int = 8  # transitions per SGD update, one update per lockstep action
  priority_exponent: float = 0.6  # sampling weight |TD error|^alpha (0: uniform)
  target_update_period: int = 50  # SGD updates between target-network copies
  checkpoint_every: int = 25  # host iterations between checkpoints
  curve_window: int = 200  # attempts in the sliding window of the training curves


@dataclasses.dataclass(frozen=True)
class Config:
  scene: SceneConfig = SceneConfig()
  env: EnvConfig = EnvConfig()
  perception: PerceptionConfig = PerceptionConfig()
  network: NetworkConfig = NetworkConfig()
  train: TrainConfig = TrainConfig()
  num_envs: int = 8
  seed: int = 0


PRESETS = ('default', 'paper', 'tiny')  # modules of mvcoba_jax.presets


def load_preset(preset: str | pathlib.Path) -> Config:
  """Config returned by `get_config()` of a preset named in `PRESETS` or of a preset file."""
  if str(preset) in PRESETS:
    module = importlib.import_module(f'mvcoba_jax.presets.{preset}')
  else:
    path = pathlib.Path(preset)
    if not path.is_file():
      raise ConfigError(f'config preset {path}: neither a file nor one of {", ".join(PRESETS)}')
    spec = importlib.util.spec_from_file_location(f'mvcoba_preset_{path.stem}', path)
    module = importlib.util.module_from_spec(spec)
    try:
      spec.loader.exec_module(module)
    except Exception as e:  # a user's Python file: any error is theirs to see, named
      raise ConfigError(f'config preset {path}: {type(e).__name__}: {e}') from None
  if not hasattr(module, 'get_config'):
    raise ConfigError(f'config preset {preset} defines no get_config()')
  return module.get_config()


def _parse(text: str, tp, key: str):
  origin = typing.get_origin(tp)
  try:
    if tp is bool:
      if text.lower() not in ('true', 'false', '1', '0'):
        raise ValueError(text)
      return text.lower() in ('true', '1')
    if tp in (int, float, str):
      return tp(text)
    if origin is tuple:
      args = typing.get_args(tp)
      if args == (tuple[str, int], Ellipsis):  # pool: 'cube:3,disk:1'
        return tuple((name, int(n)) for name, n in (item.split(':') for item in text.split(',')))
      if len(args) == 2 and args[1] is Ellipsis:
        return tuple(_parse(t, args[0], key) for t in text.split(',') if t)
      parts = text.split(',')
      if len(parts) != len(args):
        raise ValueError(f'expected {len(args)} comma-separated values')
      return tuple(_parse(t, a, key) for t, a in zip(parts, args))
  except ValueError as e:
    raise ConfigError(f'override {key}={text!r}: cannot parse as {tp}: {e}') from None
  raise ConfigError(f'override {key}: fields of type {tp} cannot be set from the command line')


def override(config, assignment: str):
  """Config with one `dotted.key=value` assignment applied."""
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

  return apply(config, path)


def resolve(preset: str | pathlib.Path | None, overrides: typing.Sequence[str] = ()) -> Config:
  """The preset (or the default preset) with `overrides` applied in order."""
  if preset is None:
    preset = 'default'
  config = load_preset(preset)
  for assignment in overrides:
    config = override(config, assignment)
  return config


def to_dict(config) -> dict:
  return dataclasses.asdict(config)


def from_dict(data: dict, cls=Config, where: str = 'config'):
  """The frozen `cls` dataclass of a `config.to_dict` dict (as JSON holds it: lists for tuples).

  Missing fields keep their defaults, so older config.json files still load (`defaulted` names
  them); unknown ones fail.
  """
  fields = {f.name for f in dataclasses.fields(cls)}
  data = {k: v for k, v in data.items() if k not in RETIRED.get(cls, ())}
  unknown = sorted(set(data) - fields)
  if unknown:
    raise ConfigError(f'{where}: unknown keys {", ".join(unknown)} for {cls.__name__}')
  hints = typing.get_type_hints(cls)
  return cls(**{k: _value(v, hints[k], f'{where}.{k}') for k, v in data.items()})


# Fields that saved configs may hold and that no longer exist: dropped when read. The training
# failure limit became `env.max_failures`, shared with evaluation (its default, 5, is the paper's).
RETIRED = {TrainConfig: ('max_consecutive_failures',)}

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
      if prefix + f.name not in RUNTIME_FIELDS:
        found[prefix + f.name] = value
    elif dataclasses.is_dataclass(value):
      found.update(defaulted(data[f.name], value, f'{prefix}{f.name}.'))
  return found


def _value(value, tp, where: str):
  if dataclasses.is_dataclass(tp):
    return from_dict(value, tp, where)
  if typing.get_origin(tp) is tuple:
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
