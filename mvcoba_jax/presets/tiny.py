"""Tiny preset for tests and smoke runs: two cubes and two flat boxes, coarse cameras and grid,
a small network and a few training actions."""
import dataclasses

from mvcoba_jax.config import (
  CameraConfig,
  Config,
  EnvConfig,
  NetworkConfig,
  PerceptionConfig,
  SceneConfig,
  TrainConfig,
)


def get_config() -> Config:
  cameras = tuple(CameraConfig(pos=c.pos, width=80, height=80) for c in SceneConfig().cameras)
  scene = SceneConfig(pool=(('cube', 2), ('flat_box', 2)), max_geom_pairs=8,
                      max_contact_points=64, cameras=cameras)
  train = dataclasses.replace(TrainConfig(), total_actions=8, steps_per_iteration=2,
                              replay_capacity=16, batch_size=4, checkpoint_every=1,
                              target_update_period=2, epsilon_decay_actions=8)
  return Config(scene=scene, env=dataclasses.replace(EnvConfig(), num_objects=2),
                perception=PerceptionConfig(heightmap_resolution=0.008),
                network=NetworkConfig(features=(8, 16), groups=4), train=train, num_envs=2)
