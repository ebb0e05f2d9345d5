"""Whether fields that are each valid fit together: `validate`, which every way of making a
config (a preset, overrides, a saved config.json) ends with."""
from __future__ import annotations

from mvcoba_jax import methods
from mvcoba_jax.sim import shapes
from mvcoba_jax.config.schema import (ACTIVATION_LIMIT_BYTES, DENSENET_GROWTH, PHASE_LIMIT_S,
                                      REPLAY_LIMIT_BYTES, Config, ConfigError)

CONTACTS_PER_OBJECT = 4  # a box resting on the table touches it at its four corners


def validate(config: Config) -> Config:
  """Raises ConfigError when fields that are each valid do not fit together; returns `config`.

  `resolve` and `from_dict` call it, after every override is in (so overrides can come in any
  order); the fields themselves are checked when each dataclass is built.
  """
  _parts_fit(config)
  _method_fits(config)
  _memory_fits(config)
  return config


def _parts_fit(config: Config) -> None:
  """Relations between fields of the scene, episode, perception and learning."""
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
  if env.grasp_depth >= scene.gripper.finger_length:
    raise ConfigError(f'env.grasp_depth={env.grasp_depth!r} must be below '
                      f'scene.gripper.finger_length={scene.gripper.finger_length!r}: the palm '
                      'would press on what the fingers reach for')
  if config.perception.change_min >= config.perception.change_max:
    raise ConfigError(f'perception.change_min={config.perception.change_min!r} must be below '
                      f'perception.change_max={config.perception.change_max!r}')
  if config.perception.failed_grasp_retries and config.perception.failed_grasp_changes:
    raise ConfigError(f'perception.failed_grasp_retries={config.perception.failed_grasp_retries} '
                      'needs perception.failed_grasp_changes=false (with it on, a failed grasp '
                      'that moved the scene is change and the rule grasps again anyway)')
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
  if scene.backend in ('mjx', 'warp'):
    _contact_caps_fit(scene, env)
  if scene.backend == 'mjx' and scene.noslip_iterations:
    raise ConfigError(f'scene.noslip_iterations={scene.noslip_iterations} needs the native or '
                      'warp backend: MJX has no noslip pass (it would run without one)')
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


def _contact_caps_fit(scene, env) -> None:
  """MJX and Warp keep at most `max_geom_pairs` pairs and `max_contact_points` points a step and
  drop the rest: a settled drop needs a pair for each of its objects' convex parts on the table
  (the `num_objects` with the most parts) and CONTACTS_PER_OBJECT points an object."""
  parts = sorted(((len(shapes.shape(name).parts), name) for name, count in scene.pool
                  for _ in range(count)), reverse=True)[:env.num_objects]
  pairs = sum(n for n, _ in parts)
  if scene.max_contact_points < CONTACTS_PER_OBJECT * env.num_objects or (
      scene.max_geom_pairs < pairs):
    most, name = parts[0]
    raise ConfigError(
        f'scene.max_contact_points={scene.max_contact_points} and scene.max_geom_pairs='
        f'{scene.max_geom_pairs} on the {scene.backend} backend: a settled drop of '
        f'env.num_objects={env.num_objects} needs at least '
        f'{CONTACTS_PER_OBJECT * env.num_objects} contact points and a geom pair for each of '
        f'its objects\' {pairs} convex parts on the table ({name}: {most} parts), or objects '
        'fall through it')


def _method_fits(config: Config) -> None:
  """The method is registered and the scene holds the camera views it reads."""
  net, scene = config.network, config.scene
  if net.method not in methods.names():
    raise ConfigError(f'network.method={net.method!r}: allowed values are '
                      f'{", ".join(methods.names())}')
  views = methods.get(net.method).views
  if max(views) >= len(scene.cameras):
    raise ConfigError(f'network.method={net.method!r} reads camera views {views}; '
                      f'scene.cameras holds {len(scene.cameras)} (choosing the method with '
                      '--method or --set network.method sets the cameras it needs)')


def _memory_fits(config: Config) -> None:
  """The replay and one acting forward fit in memory (`REPLAY_LIMIT_BYTES`,
  `ACTIVATION_LIMIT_BYTES`)."""
  scene, env, net, train = config.scene, config.env, config.network, config.train
  side = round(2 * scene.workspace_half / config.perception.heightmap_resolution)
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
