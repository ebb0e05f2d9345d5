"""Shared test setup: the entry points' process set-up, with the compilation cache in the
repository's git-ignored .cache/jax (subprocesses that the tests start inherit it)."""
import os
import pathlib

from mvcoba_jax import runtime

os.environ.setdefault('MVCOBA_JAX_CACHE',
                      str(pathlib.Path(__file__).resolve().parent.parent / '.cache' / 'jax'))
runtime.setup()
