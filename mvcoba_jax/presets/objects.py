"""Objects preset: the default recipe with procedural training objects beside the blocks (docs/
objects.md): one slot each of the 14 shapes in `mvcoba_jax/sim/objects/procedural` (convex
polyhedra, rounded solids, bars, L, T and U shapes, square rings; `sim/procedural.py`, seed 0), so
a drop of 10 from the 26 slots holds about half blocks, half new shapes. For policies that meet
objects other than the paper's blocks."""
import dataclasses

from mvcoba_jax.config import Config
from mvcoba_jax.presets import default
from mvcoba_jax.sim import procedural


def get_config() -> Config:
  config = default.get_config()
  pool = config.scene.pool + tuple((str(p), 1) for p in procedural.training_objects())
  scene = dataclasses.replace(config.scene, pool=pool,
                              max_contact_points=2 * config.scene.max_contact_points,
                              max_geom_pairs=2 * config.scene.max_geom_pairs)
  return dataclasses.replace(config, scene=scene)
