"""Configuration of the simulated tabletop: the compiled scene, its cameras and the episode.

The training configuration (`mvcoba_jax.config.Config`) holds these as its `scene` and `env`;
the simulator is built from those two alone (`TabletopConfig`, `Config.tabletop`). Every config
dataclass checks its fields' types and ranges when it is built (`check`), so presets, `--set`
overrides, saved config.json files and exported model.json files all pass the same gate.
"""
from __future__ import annotations

import dataclasses
import functools
import importlib.util
import math
import typing

from mvcoba_jax.sim import meshes, shapes
from mvcoba_jax.sim.contract import RANGES
from mvcoba_jax.sim.errors import Error

BACKENDS = ('auto', 'native', 'mjx', 'warp')
DROPS = ('spread', 'heap')  # env.drop


class ConfigError(Error):
  """A preset, override or saved config that does not fit the configuration schema."""


@dataclasses.dataclass(frozen=True)
class Between:
  """A numeric range; `low_open` excludes its lower end."""
  low: float
  high: float
  low_open: bool = False

  def __contains__(self, value) -> bool:
    return (self.low < value if self.low_open else self.low <= value) and value <= self.high

  def __str__(self) -> str:
    return f'{"(" if self.low_open else "["}{self.low:g}, {self.high:g}]'


@functools.cache
def _hints(cls) -> dict:
  return typing.get_type_hints(cls)


def _type_problem(value, tp) -> str | None:
  """Why `value` is not of the declared type `tp`, or None."""
  origin = typing.get_origin(tp)
  if tp is bool:
    return None if isinstance(value, bool) else 'expected true or false'
  if tp is int:
    return None if isinstance(value, int) and not isinstance(value, bool) else 'expected an integer'
  if tp is float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
      return 'expected a number'
    return None if math.isfinite(value) else 'expected a finite number'
  if tp is str:
    return None if isinstance(value, str) else 'expected a string'
  if dataclasses.is_dataclass(tp):
    return None if isinstance(value, tp) else f'expected a {tp.__name__}'
  if origin is tuple:
    if not isinstance(value, tuple):
      return 'expected a sequence'
    args = typing.get_args(tp)
    if len(args) == 2 and args[1] is Ellipsis:
      args = (args[0],) * len(value)
    elif len(args) != len(value):
      return f'expected {len(args)} values, got {len(value)}'
    for i, (v, a) in enumerate(zip(value, args)):
      problem = _type_problem(v, a)
      if problem:
        return f'[{i}]: {problem}'
    return None
  raise TypeError(f'no check for fields of type {tp}')


def check(obj, prefix: str, rules: dict) -> None:
  """Raises ConfigError naming `prefix` + field when a field of `obj` has the wrong type, lies
  outside its `rules` entry (a Between, or a tuple of allowed strings), or holds a sequence one
  of whose numbers does (a Between applies to every number in it)."""
  hints = _hints(type(obj))
  for field in dataclasses.fields(obj):
    key, value = f'{prefix}{field.name}', getattr(obj, field.name)
    problem = _type_problem(value, hints[field.name])
    if problem:
      raise ConfigError(f'{key}={value!r}: {problem}')
    rule = rules.get(field.name)
    if isinstance(rule, Between):
      for number in _numbers(value):
        if number not in rule:
          raise ConfigError(f'{key}={value!r}: allowed range {rule}')
    elif rule is not None and value not in rule:
      raise ConfigError(f'{key}={value!r}: allowed values are {", ".join(rule)}')


def _numbers(value):
  if isinstance(value, tuple):
    for v in value:
      yield from _numbers(v)
  elif isinstance(value, (int, float)) and not isinstance(value, bool):
    yield value


@dataclasses.dataclass(frozen=True)
class CameraConfig:
  """A pinhole RGB-D camera looking from `pos` at `target`."""
  pos: tuple[float, float, float]
  target: tuple[float, float, float] = (0.0, 0.0, 0.0)
  width: int = 160
  height: int = 160
  fovy_deg: float = 38.0

  def __post_init__(self):
    check(self, 'scene.cameras[].', {'pos': Between(-10, 10), 'target': Between(-10, 10),
                                     'width': Between(8, 4096), 'height': Between(8, 4096),
                                     'fovy_deg': Between(1, 179)})


@dataclasses.dataclass(frozen=True)
class GripperConfig:
  """The two-finger parallel gripper, as one description that the scene, the primitives, the
  grasp-success rule, CPG's landing zones and the pictures read. Each finger is a box: `width`
  across the closing direction, `thickness` along it, `length` below the palm. The defaults are
  the RG2-like gripper every landed figure used; `sim/grippers.py` holds the presets and the
  sources of their numbers."""
  name: str = 'rg2'
  finger_width: float = 0.02
  finger_thickness: float = 0.01
  finger_length: float = 0.06
  max_opening: float = 0.11  # gap between the open fingers (m)
  palm: tuple[float, float, float] = (0.03, 0.15, 0.02)  # full size (m), y along the closing
  finger_force: float = 15.0  # N: each finger's drive, at most
  finger_friction: float = 1.5

  def __post_init__(self):
    check(self, 'scene.gripper.', {
        'finger_width': Between(0.002, 0.1), 'finger_thickness': Between(0.001, 0.05),
        'finger_length': Between(0.01, 0.2),
        'max_opening': Between(*RANGES['scene.gripper.max_opening']),
        'palm': Between(0.001, 0.5), 'finger_force': Between(0, 1000, low_open=True),
        'finger_friction': Between(0, 10, low_open=True)})
    if self.max_opening <= 2 * self.finger_thickness:
      raise ConfigError(f'scene.gripper.max_opening={self.max_opening!r} must exceed twice '
                        f'scene.gripper.finger_thickness ({2 * self.finger_thickness:g})')


@dataclasses.dataclass(frozen=True)
class SceneConfig:
  """What goes into the compiled MuJoCo model, and which engine steps it."""
  # 'native': MuJoCo's C engine and mj_ray on CPU threads; 'mjx': MJX's JAX implementation,
  # traced into the jitted program; 'warp': MuJoCo Warp and its batch renderer, in the jitted
  # program (NVIDIA GPUs; needs the gpu extra); 'auto': the fastest measured on this kind of
  # device (`physics.resolve_backend`).
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
  # MuJoCo's noslip pass after each step's solve: soft contacts let a settled heap creep (objects
  # on others slide centimetres in a minute with no action and some leave the table,
  # benchmarks/heap_creep.py); the pass stops that slip. Native and Warp; MJX has no such pass.
  noslip_iterations: int = 0
  # Contact stiffness (MuJoCo solref time constant, s). 2 x timestep, the stiffest MuJoCo allows:
  # with its default 0.02 the fingers press packed blocks millimetres into the table and lift
  # them with no push (benchmarks/ordered_graspability.py).
  contact_timeconst: float = 0.008
  friction: float = 1.0
  gripper: GripperConfig = GripperConfig()
  # The most the gripper's vertical drive presses down (N), as a real arm's force limit would:
  # fingers that land on a neighbouring block stop on its top instead of sinking millimetres
  # into it and prying packed blocks apart (benchmarks/ordered_graspability.py).
  press_force: float = 5.0
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

  def __post_init__(self):
    check(self, 'scene.', {
        'backend': BACKENDS, 'native_threads': Between(0, 1024),
        'pool': Between(0, 256), 'workspace_half': Between(*RANGES['scene.workspace_half']),
        'workspace_top': Between(0.05, 2.0), 'timestep': Between(0.0001, 0.02),
        'iterations': Between(1, 1000), 'ls_iterations': Between(1, 1000),
        'noslip_iterations': Between(0, 1000),
        'contact_timeconst': Between(0, 1, low_open=True),
        'friction': Between(0, 10, low_open=True),
        'press_force': Between(0, 60, low_open=True),
        'object_density': Between(1, 100000), 'max_geom_pairs': Between(1, 100000),
        'max_contact_points': Between(1, 1000000), 'occluders': Between(0, 1, low_open=True)})
    try:
      pool = tuple((shapes.reference(n), c) for n, c in self.pool)
      extents = [shapes.shape(name).rest_extent for name, _ in pool]
    except meshes.MeshError as e:
      raise ConfigError(f'scene.pool: {e}') from None
    names = [name for name, _ in pool]
    if len(set(names)) < len(names) or not self.num_slots:
      raise ConfigError(f'scene.pool={self.pool!r}: expected distinct shapes (blocks: '
                        f'{", ".join(shapes.SHAPE_NAMES)}; or mesh files and folders) with at '
                        'least one slot in all')
    object.__setattr__(self, 'pool', pool)  # mesh paths absolute: the config names one file
    for name, extent in zip(names, extents):
      if max(extent[:2]) > 2 * self.workspace_half:
        raise ConfigError(f'scene.pool: {name}: {max(extent[:2]):g} m across, wider than the '
                          f'workspace ({2 * self.workspace_half:g} m, scene.workspace_half)')
    if not self.cameras:
      raise ConfigError('scene.cameras: at least one camera')
    if self.backend == 'warp' and importlib.util.find_spec('warp') is None:
      raise ConfigError("scene.backend=warp needs NVIDIA Warp: pip install -e '.[gpu]' "
                        "(or 'mujoco-mjx[warp]')")
    if self.contact_timeconst < 2 * self.timestep:
      raise ConfigError(f'scene.contact_timeconst={self.contact_timeconst!r} is below 2 x '
                        f'scene.timestep ({2 * self.timestep:g}), which MuJoCo would use instead')

  @property
  def num_slots(self) -> int:
    return sum(n for _, n in self.pool)


@dataclasses.dataclass(frozen=True)
class EnvConfig:
  """Episode and primitive parameters."""
  num_objects: int = 10  # objects dropped by reset(key)
  # How reset(key) drops them: 'spread', set down apart in their rest pose over the workspace
  # less `drop_margin`; 'heap', in a random 3-D orientation into the central square of half
  # side `heap_half`, so they land on each other (the MV-COBA authors' training scenes).
  drop: str = 'spread'
  heap_half: float = 0.125
  # Share of reset(key)'s tabletops with an occluder between one camera (drawn) and the table,
  # hiding all (occluder slot 0) or part (slot 1, shifted sideways) of what that camera sees.
  occluded_share: float = 0.0
  # Share of reset(key)'s tabletops laid out packed instead (beyond the paper, whose training
  # drops are never packed): one of the scene's packed arrangements of the training types (rows,
  # grids, L shapes, mixed rows; `tabletop.packed_bank`, `sim/arrangements.py`), with gaps the
  # fingers cannot enter, turned by a drawn yaw about a drawn centre.
  packed_share: float = 0.0
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
  # An episode ends after more consecutive failed actions than this, in training (new objects are
  # dropped) and in evaluation (the run ends; the paper's completion rule counts 5).
  max_failures: int = 5

  def __post_init__(self):
    check(self, 'env.', {
        'num_objects': Between(1, 256), 'num_rotations': Between(*RANGES['env.num_rotations']),
        'drop': DROPS,
        'heap_half': Between(0.02, 1), 'occluded_share': Between(0, 1),
        'packed_share': Between(0, 1),
        'settle_steps': Between(0, 100000), 'drop_margin': Between(0, 0.2),
        'layer_height': Between(0, 1, low_open=True), 'grasp_depth': Between(0, 0.2),
        'lift_height': Between(0, 1, low_open=True), 'approach_height': Between(0, 1, low_open=True),
        'descend_speed': Between(0, 10, low_open=True), 'lift_speed': Between(0, 10, low_open=True),
        'close_time': Between(0, 5, low_open=True), 'hold_time': Between(0, 5),
        'push_height': Between(0, 0.2), 'push_length': Between(*RANGES['env.push_length']),
        'push_speed': Between(0, 10, low_open=True), 'min_tip_height': Between(0, 0.1),
        'max_qvel': Between(0, 1e6, low_open=True), 'max_failures': Between(0, 1000)})


@dataclasses.dataclass(frozen=True)
class TabletopConfig:
  """What a `Tabletop` reads: the scene and the episode, nothing of perception or training."""
  scene: SceneConfig = SceneConfig()
  env: EnvConfig = EnvConfig()
