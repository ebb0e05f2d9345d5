"""The paper's perception: 224 x 224 heightmaps at 2 mm from 320 x 320 cameras (GPU-sized),
with the default preset's learning recipe."""
import dataclasses

from mvcoba_jax.config import CameraConfig, Config, PerceptionConfig
from mvcoba_jax.presets import default


def get_config() -> Config:
  config = default.get_config()
  cameras = tuple(CameraConfig(pos=c.pos, width=320, height=320) for c in config.scene.cameras)
  return dataclasses.replace(config, scene=dataclasses.replace(config.scene, cameras=cameras),
                             perception=PerceptionConfig(heightmap_resolution=0.002))
