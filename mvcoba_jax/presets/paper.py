"""The paper's perception: 224 x 224 heightmaps at 2 mm from 320 x 320 cameras (GPU-sized)."""
import dataclasses

from mvcoba_jax.config import CameraConfig, Config, PerceptionConfig, SceneConfig


def get_config() -> Config:
  cameras = tuple(CameraConfig(pos=c.pos, width=320, height=320) for c in SceneConfig().cameras)
  return Config(scene=dataclasses.replace(SceneConfig(), cameras=cameras),
                perception=PerceptionConfig(heightmap_resolution=0.002))
