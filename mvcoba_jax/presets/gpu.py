"""GPU preset: the default preset's recipe on MuJoCo Warp (`scene.backend=warp`: physics and both
cameras on the GPU, inside the jitted step) with 64 tabletops in lockstep and the default's replay
ratio kept (`train.replay_ratio=1`: 8 updates of 8 transitions after each lockstep action, as the
default samples 8 per 8 new ones). Needs `pip install -e '.[gpu]'`. With the ratio kept, 64
tabletops learned as 8 do for equal actions on the validation suites; with one update per action
they lost 17 to 28 points of grasp success (docs/results/warp.md, measured on the CPU). Its speed
is not yet measured on an accelerator."""
import dataclasses

from mvcoba_jax.config import Config
from mvcoba_jax.presets import default


def get_config() -> Config:
  config = default.get_config()
  return dataclasses.replace(
      config, num_envs=64, scene=dataclasses.replace(config.scene, backend='warp'),
      train=dataclasses.replace(config.train, replay_ratio=1.0))
