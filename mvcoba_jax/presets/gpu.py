"""GPU preset: the default preset's recipe on MuJoCo Warp (`scene.backend=warp`: physics and both
cameras on the GPU, inside the jitted step) with 64 tabletops in lockstep and the default's replay
ratio kept (`train.replay_ratio=1`: 8 updates of 8 transitions after each lockstep action, as the
default samples 8 per 8 new ones). Needs `pip install -e '.[gpu]'`. Its batch and speed are not
yet measured on an accelerator (docs/results/warp.md); learning at 64 tabletops with the ratio
kept is measured on the CPU there."""
import dataclasses

from mvcoba_jax.config import Config
from mvcoba_jax.presets import default


def get_config() -> Config:
  config = default.get_config()
  return dataclasses.replace(
      config, num_envs=64, scene=dataclasses.replace(config.scene, backend='warp'),
      train=dataclasses.replace(config.train, replay_ratio=1.0))
