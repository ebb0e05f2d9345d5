"""Tiny preset for tests and smoke runs: two cubes and two flat boxes, coarse cameras and grid."""
import dataclasses

from mvcoba_jax.config import CameraConfig, Config, EnvConfig, PerceptionConfig, SceneConfig


def get_config() -> Config:
  cameras = tuple(CameraConfig(pos=c.pos, width=80, height=80) for c in SceneConfig().cameras)
  scene = SceneConfig(pool=(('cube', 2), ('flat_box', 2)), max_geom_pairs=8,
                      max_contact_points=64, cameras=cameras)
  return Config(scene=scene, env=dataclasses.replace(EnvConfig(), num_objects=2),
                perception=PerceptionConfig(heightmap_resolution=0.008), num_envs=4)
