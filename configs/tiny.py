"""Tiny preset for tests and smoke runs: two cubes and two flat boxes, few environments."""
import dataclasses

from mvcoba_jax.config import Config, EnvConfig, SceneConfig


def get_config() -> Config:
  scene = SceneConfig(pool=(('cube', 2), ('flat_box', 2)), max_geom_pairs=8,
                      max_contact_points=64)
  return Config(scene=scene, env=dataclasses.replace(EnvConfig(), num_objects=2), num_envs=4)
