"""The learning recipe MV-COBA, grasp-only, MVP and CPG train with in the paper's comparison
(`reproduction.RECIPES`): the MV-COBA authors' recipe (the `authors` preset) without its update's
fresh transitions, and a quarter of the training drops with an occluder hiding all or part of one
camera's view (`env.occluded_share`, beyond the paper), both chosen by the recipe study on
validation cases (docs/results/recipe.md). It adds nothing to any method's rule or perception:
the methods differ only where the paper says they do. 6000 actions (the comparison trains each
for the paper's 3000)."""
import dataclasses

from mvcoba_jax.config import Config
from mvcoba_jax.presets import authors


def get_config() -> Config:
  config = authors.get_config()
  return dataclasses.replace(
      config, train=dataclasses.replace(config.train, fresh_in_batch=False, total_actions=6000),
      env=dataclasses.replace(config.env, occluded_share=0.25))
