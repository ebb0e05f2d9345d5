"""Configuration: frozen dataclasses, presets in `configs/<name>.py`, `key=value` overrides.

A preset file defines `get_config() -> Config`. Overrides use dotted paths
(`env.num_objects=5`, `scene.pool=cube:3,disk:1`) and are parsed by the field's type, so a typo
or a bad value fails with a message that names the key.
"""
from __future__ import annotations

import dataclasses
import importlib.util
import pathlib
import typing


@dataclasses.dataclass(frozen=True)
class CameraConfig:
  """A pinhole RGB-D camera looking from `pos` at `target`."""
  pos: tuple[float, float, float]
  target: tuple[float, float, float] = (0.0, 0.0, 0.0)
  width: int = 160
  height: int = 160
  fovy_deg: float = 38.0


@dataclasses.dataclass(frozen=True)
class SceneConfig:
  """What goes into the compiled MuJoCo model, and which engine steps it."""
  # 'native': MuJoCo's C engine and mj_ray on CPU threads; 'mjx': MJX, traced into the jitted
  # program (the path for GPUs and TPUs); 'auto': native when JAX's default device is a CPU.
  backend: str = 'auto'
  native_threads: int = 0  # threads of the native backend; 0: every core this process may use
  # Object slots: (shape name, count). Objects not in play are parked away from the table.
  # The default holds every public VPG test case and leaves a choice for random drops.
  pool: tuple[tuple[str, int], ...] = (
      ('cube', 2), ('tall_box', 2), ('flat_box', 1), ('prism', 2), ('arch', 2),
      ('cylinder', 1), ('disk', 1), ('octagon', 1))
  workspace_half: float = 0.224  # workspace is x, y in [-h, h]
  workspace_top: float = 0.4
  timestep: float = 0.004
  iterations: int = 4
  ls_iterations: int = 6
  # Contact stiffness (MuJoCo solref time constant, s). 2 x timestep, the stiffest MuJoCo allows:
  # with its default 0.02 the fingers press packed blocks millimetres into the table and lift
  # them with no push (benchmarks/ordered_graspability.py).
  contact_timeconst: float = 0.008
  friction: float = 1.0
  finger_friction: float = 1.5
  object_density: float = 500.0
  # MJX only (native MuJoCo has no caps): pairs and contact points kept per step.
  max_geom_pairs: int = 24
  max_contact_points: int = 96
  # Opposite sides of the workspace; at 160 x 160 pixels each sees ~97% of a 112 x 112 grid.
  cameras: tuple[CameraConfig, ...] = (
      CameraConfig(pos=(0.35, 0.0, 0.65)), CameraConfig(pos=(-0.35, 0.0, 0.65)))
  # Occluder slots (box half sizes, thin along x to face the cameras): one that can hide the
  # whole workspace from a camera, two partial ones. Scenarios pose them; unused ones are parked.
  occluders: tuple[tuple[float, float, float], ...] = (
      (0.01, 0.12, 0.12), (0.01, 0.05, 0.05), (0.01, 0.05, 0.05))

  @property
  def num_slots(self) -> int:
    return sum(n for _, n in self.pool)


@dataclasses.dataclass(frozen=True)
class EnvConfig:
  """Episode and primitive parameters."""
  num_objects: int = 10  # objects dropped by reset(key)
  num_rotations: int = 16
  settle_steps: int = 375  # physics steps (1.5 s) for placed or dropped objects to come to rest
  drop_margin: float = 0.06  # keep dropped object centres this far inside the workspace
  layer_height: float = 0.12  # vertical spacing of drop layers
  # Grasp: descend to `grasp_depth` below the surface, close, lift `lift_height`.
  grasp_depth: float = 0.03
  lift_height: float = 0.30
  approach_height: float = 0.08
  descend_speed: float = 0.4
  lift_speed: float = 0.6
  close_time: float = 0.2
  hold_time: float = 0.04
  # Push: fingertips `push_height` above the table, move `push_length` along the direction.
  push_height: float = 0.01
  push_length: float = 0.10
  push_speed: float = 0.25
  min_tip_height: float = 0.005
  # Health: any |qvel| above this (or a non-finite value) marks the environment unhealthy.
  max_qvel: float = 50.0


@dataclasses.dataclass(frozen=True)
class PerceptionConfig:
  """Heightmaps and change observation (SPEC section 4)."""
  heightmap_resolution: float = 0.004  # m per cell: 112 x 112 (the paper: 0.002 -> 224 x 224)
  # Change is observed when more cells than `change_area` / resolution^2 changed height by
  # between `change_min` and `change_max`: VPG's 300 cells at 2 mm, the same area at any grid.
  change_area: float = 300 * 0.002 ** 2
  change_min: float = 0.01
  change_max: float = 0.3


@dataclasses.dataclass(frozen=True)
class NetworkConfig:
  """The Q-network (SPEC section 5). `method` picks the architecture and the action rule."""
  method: str = 'mvcoba'  # a method of mvcoba_jax/methods.py
  trunk: str = 'small'  # 'small' (CPU-sized, from scratch) or 'densenet121' (GPU-sized)
  stem_patch: int = 4  # the stem turns patch x patch cells into one feature vector
  features: tuple[int, ...] = (32, 64, 64)  # channels of the trunk stages (small trunk)
  groups: int = 8  # GroupNorm groups


@dataclasses.dataclass(frozen=True)
class TrainConfig:
  """Q-learning (SPEC section 6)."""
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
  max_consecutive_failures: int = 10  # an episode with more is stuck and gets new objects
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


class ConfigError(ValueError):
  """A preset or override that does not fit the configuration schema."""


def load_preset(path: str | pathlib.Path) -> Config:
  """Config returned by `get_config()` of the preset file at `path`."""
  path = pathlib.Path(path)
  if not path.is_file():
    raise ConfigError(f'config preset {path} does not exist')
  spec = importlib.util.spec_from_file_location(f'mvcoba_preset_{path.stem}', path)
  module = importlib.util.module_from_spec(spec)
  spec.loader.exec_module(module)
  if not hasattr(module, 'get_config'):
    raise ConfigError(f'config preset {path} defines no get_config()')
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
    preset = pathlib.Path(__file__).resolve().parent.parent / 'configs' / 'default.py'
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
  unknown = sorted(set(data) - fields)
  if unknown:
    raise ConfigError(f'{where}: unknown keys {", ".join(unknown)} for {cls.__name__}')
  hints = typing.get_type_hints(cls)
  return cls(**{k: _value(v, hints[k], f'{where}.{k}') for k, v in data.items()})


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
                      help='preset file (default: configs/default.py)')
  parser.add_argument('--set', dest='overrides', action='append', default=[],
                      metavar='KEY=VALUE', help='override a config field, e.g. env.num_objects=5')


def from_arguments(args) -> Config:
  return resolve(args.config, args.overrides)
