"""Configs as saved in config.json, checkpoints and model.json: to and from dicts, the names old
files still hold (`RETIRED`, `LEGACY`), the fields that only choose where a run computes, and
what a policy was trained as."""
from __future__ import annotations

import dataclasses
import json
import typing

from mvcoba_jax.config.schema import (
  Config,
  ConfigError,
  EnvConfig,
  GripperConfig,
  NetworkConfig,
  PerceptionConfig,
  SceneConfig,
  TrainConfig,
)
from mvcoba_jax.config.validation import validate


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
  for old, (group, field) in MOVED.get(cls, {}).items():
    if old in data:
      data = {**data, group: {**data[group], field: data[old]}}
      del data[old]
  unknown = sorted(set(data) - fields)
  if unknown:
    raise ConfigError(f'{where}: unknown keys {", ".join(unknown)} for {cls.__name__}')
  hints = typing.get_type_hints(cls)
  config = cls(**{k: _value(v, hints[k], f'{where}.{k}') for k, v in data.items()})
  return validate(config) if cls is Config else config


# Fields that saved configs may hold and that no longer exist: dropped when read. The training
# failure limit became `env.max_failures`, shared with evaluation (its default, 5, is the paper's).
RETIRED = {TrainConfig: ('max_consecutive_failures',)}

# Fields that moved into a group, with the group's field that holds them now: a saved config's
# value is kept there. The scene's finger friction is the gripper's.
MOVED = {SceneConfig: {'finger_friction': ('gripper', 'finger_friction')}}

# Fields added after runs were saved without them, with the value those runs used (which is not
# the current default): a saved config that lacks them gets that value, without a warning.
LEGACY = {TrainConfig: {'target': 'network', 'failed_grasp_reward': 0.5,
                        'no_change_push_reward': 0.0, 'bootstrap_no_change': True,
                        'future_max': 'rule', 'grasp_symmetry': False, 'fresh_in_batch': False,
                        'quarter_turns': False, 'replay_ratio': 0.0, 'lost_object_reward': 0.0},
          EnvConfig: {'drop': 'spread', 'heap_half': 0.125, 'occluded_share': 0.0,
                      'packed_share': 0.0},
          NetworkConfig: {'pad_to_diagonal': False, 'shared_stages': 0, 'suppress': False,
                          'push_room': 0.0},
          PerceptionConfig: {'failed_grasp_changes': True, 'fill_unseen': False,
                             'failed_grasp_retries': 0},
          SceneConfig: {'gripper': dataclasses.asdict(GripperConfig()), 'noslip_iterations': 0}}

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
