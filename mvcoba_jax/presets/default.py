"""Default preset: the paper's training protocol (10 objects dropped at random), CPU-sized."""
from mvcoba_jax.config import Config


def get_config() -> Config:
  return Config()
