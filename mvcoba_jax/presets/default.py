"""Default preset: the MV-COBA authors' learning recipe (the `authors` preset), chosen by the
recipe study on validation cases (docs/results/recipe.md): ahead of the paper's text on every
validation suite at three seeds and 5 runs per case, at 0.74x its training speed. `paper_text`
is the paper text's recipe, what this preset was before."""
from mvcoba_jax.presets.authors import get_config

__all__ = ['get_config']
