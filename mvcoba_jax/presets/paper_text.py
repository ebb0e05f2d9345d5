"""The learning recipe as the paper's text gives it, at the default preset's scale: a failed
grasp that changed the scene earns 0.5, a push that changed nothing 0, every action bootstraps
from the primitive the rule picks next, one replayed transition per action, objects set down
apart over the workspace."""
from mvcoba_jax.config import Config


def get_config() -> Config:
  return Config()
