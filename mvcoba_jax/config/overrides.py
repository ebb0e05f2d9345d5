"""`key=value` overrides (`--set`): dotted paths (`env.num_objects=5`, `scene.pool=cube:3,disk:1`)
parsed by the field's type, so a typo or a bad value fails with a message that names the key."""
from __future__ import annotations

import dataclasses
import math
import re
import typing

from mvcoba_jax import methods
from mvcoba_jax.sim import grippers
from mvcoba_jax.config.schema import Config, ConfigError, GripperConfig
from mvcoba_jax.config.validation import validate


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
    items = [item.rsplit(':', 1) for item in text.split(',')]
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
    if isinstance(value, GripperConfig):  # a gripper by its preset's name
      return dataclasses.replace(node, **{names[0]: grippers.preset(text.strip())})
    if dataclasses.is_dataclass(value):
      raise ConfigError(f'config key {key!r} is a group; set one of its fields')
    return dataclasses.replace(node, **{names[0]: _parse(text.strip(), hints[names[0]], key)})

  config = apply(config, path)
  if path == ['network', 'method'] and config.network.method in methods.names():
    cameras = methods.get(config.network.method).cameras
    if cameras:  # a method that moves its camera brings its poses
      config = dataclasses.replace(config, scene=dataclasses.replace(config.scene, cameras=cameras))
  return config


# What a trained policy's network was built for: no --set of these at evaluation, but for the
# `ACTING_RULE`.
FIXED_BY_TRAINING = ('network.', 'perception.', 'env.num_rotations', 'scene.workspace_half')
# What the change rule makes of a grasp that held nothing: which primitive comes next, not what
# the network reads, so a trained policy may act under other values than it trained with.
ACTING_RULE = ('perception.failed_grasp_changes', 'perception.failed_grasp_retries')


def evaluated(config: Config, overrides: typing.Sequence[str]) -> Config:
  """A trained policy's config with an evaluation's `--set` overrides (physics, episode, the
  `ACTING_RULE`), which may not touch what training fixed (`FIXED_BY_TRAINING`)."""
  for assignment in overrides:
    key = assignment.split('=', 1)[0].strip()
    if key.startswith(FIXED_BY_TRAINING) and key not in ACTING_RULE:
      raise ConfigError(f'--set {key}: fixed by the trained policy\'s network (its network, '
                        'perception, rotations and workspace); it cannot change at evaluation '
                        f'(of perception only {" and ".join(ACTING_RULE)} can)')
    config = override(config, assignment)
  return validate(config)
