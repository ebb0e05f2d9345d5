"""Process-wide set-up, made once by each entry point and by the tests (`setup()`).

Nothing here happens on import: a library user who imports `mvcoba_jax` keeps their process as
it was until they call `setup()`.
"""
from __future__ import annotations

import os
import pathlib

import jax
import scipy.linalg  # noqa: F401  (loads the OpenBLAS that the limit below applies to)
import threadpoolctl


def default_cache() -> pathlib.Path:
  """$MVCOBA_JAX_CACHE, else the user's cache folder (~/.cache/mvcoba-jax/jax)."""
  if os.environ.get('MVCOBA_JAX_CACHE'):
    return pathlib.Path(os.environ['MVCOBA_JAX_CACHE'])
  base = os.environ.get('XDG_CACHE_HOME') or pathlib.Path.home() / '.cache'
  return pathlib.Path(base) / 'mvcoba-jax' / 'jax'


def setup(cache: str | os.PathLike | None = None) -> pathlib.Path:
  """Serial BLAS and the persistent compilation cache (in `cache` or `default_cache()`; MJX
  programs take 30-100 s to compile on a CPU, the training step ~20 s). Returns the folder.

  XLA already spreads work over the cores; OpenBLAS's own threads (MJX's factorizations reach it
  through jaxlib's LAPACK kernels) fought it for them: a 288-dof Cholesky took 240 ms with them
  and 0.4 ms without.
  """
  threadpoolctl.threadpool_limits(limits=1, user_api='blas')
  folder = pathlib.Path(cache) if cache else default_cache()
  folder.mkdir(parents=True, exist_ok=True)
  jax.config.update('jax_compilation_cache_dir', str(folder))
  jax.config.update('jax_persistent_cache_min_compile_time_secs', 1.0)
  jax.config.update('jax_persistent_cache_min_entry_size_bytes', 0)
  return folder
