"""Heightmaps from the cameras' point clouds, and MV-COBA's change observation.

Each camera's hits are binned into the workspace grid (`sim.contract.binned`), keeping
the highest point per cell; cells a camera does not see stay 0, as does the table. One int32
scatter-max on a packed key (height in 10 um units, then the geom id) gives the height and the
colour of the top surface in one pass.
"""
from __future__ import annotations

import jax.numpy as jnp
from flax import struct

from mvcoba_jax.config import PerceptionConfig, SceneConfig
from mvcoba_jax.sim import cameras
from mvcoba_jax.sim.contract import HEIGHT_UNIT, binned, changed_views, filled

GEOM_SLOTS = 1024  # geom ids must stay below this to fit the packed key


@struct.dataclass
class Observation:
  """The state s_t: per view a colour and a depth heightmap (height above the table)."""
  color: jnp.ndarray  # (V, R, R, 3) float 0..1
  depth: jnp.ndarray  # (V, R, R) float, m
  seen: jnp.ndarray  # (V, R, R) bool: the view has a point in the cell (else depth is 0)


def color_to_uint8(color):
  """Colour in 0..1 as uint8 0..255, rounded: the compact form the replay and run traces keep."""
  return jnp.round(jnp.clip(jnp.asarray(color), 0.0, 1.0) * 255).astype(jnp.uint8)


def grid_size(perception: PerceptionConfig, scene: SceneConfig) -> int:
  """Heightmap side in cells; the resolution must tile the workspace exactly."""
  side = 2 * scene.workspace_half / perception.heightmap_resolution
  if abs(side - round(side)) > 1e-6:
    raise ValueError(f'perception.heightmap_resolution={perception.heightmap_resolution} '
                     f'does not tile the {2 * scene.workspace_half} m workspace')
  return int(round(side))


def heightmap(image: cameras.CameraImage, colors, perception: PerceptionConfig,
              scene: SceneConfig):
  """(R, R, 3) colour, (R, R) depth heightmap and (R, R) seen mask of one camera's picture."""
  side = grid_size(perception, scene)
  cell, height = binned(image.points[..., 0], image.points[..., 1], image.points[..., 2],
                        image.hit, perception.heightmap_resolution, scene.workspace_half,
                        scene.workspace_top, jnp)
  valid = cell >= 0
  cell = jnp.where(valid, cell, side * side).reshape(-1)
  key = jnp.where(valid, height * GEOM_SLOTS + image.geom, -1).reshape(-1)
  best = jnp.full(side * side + 1, -1, jnp.int32).at[cell].max(key)[:-1].reshape(side, side)
  seen = best >= 0
  # float32, not weakly typed: a restored checkpoint (always strong) must fit the same program.
  depth = jnp.where(seen, (best // GEOM_SLOTS) * jnp.float32(HEIGHT_UNIT), jnp.float32(0.0))
  color = jnp.where(seen[..., None], colors[jnp.maximum(best % GEOM_SLOTS, 0)], 0.0)
  return color, depth, seen


def observe(env, state, config: PerceptionConfig) -> Observation:
  """Renders every camera of one environment (a `Tabletop`) and projects each into its
  heightmaps as `config` says."""
  if env.scene.mj_model.ngeom > GEOM_SLOTS:
    raise ValueError(f'the scene has {env.scene.mj_model.ngeom} geoms; heightmaps pack geom ids '
                     f'below {GEOM_SLOTS}')
  colors = cameras.geom_colors(env, state)
  maps = [heightmap(image, colors, config, env.config.scene)
          for image in cameras.render(env, state)]
  color, depth, seen = (jnp.stack(parts) for parts in zip(*maps))
  if config.fill_unseen:
    color, depth = filled(color, depth, seen, jnp)
  return Observation(color=color, depth=depth, seen=seen)


def frames_changed(before: Observation, after: Observation, config: PerceptionConfig):
  """Whether some view changed between two observations (`sim.contract.changed_views`, the
  deploy path's rule too); `sim.contract.observed_change` adds what a grasp held."""
  views = changed_views(before.depth, before.seen, after.depth, after.seen, config.change_min,
                        config.change_max, config.change_area, config.heightmap_resolution, jnp)
  return jnp.any(views, axis=-1)
