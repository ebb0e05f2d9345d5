"""Process-wide JAX settings shared by the entry points, benchmarks and tests."""
from __future__ import annotations

import os
import pathlib

import jax

REPO_ROOT = pathlib.Path(__file__).resolve().parent.parent


def enable_compilation_cache(path: str | os.PathLike | None = None) -> pathlib.Path:
  """Persists compiled XLA programs: MJX programs take 30-100 s to compile on a CPU.

  The folder defaults to `.cache/jax` in the repository (ignored by git), or $MVCOBA_JAX_CACHE.
  """
  folder = pathlib.Path(path or os.environ.get('MVCOBA_JAX_CACHE') or REPO_ROOT / '.cache' / 'jax')
  folder.mkdir(parents=True, exist_ok=True)
  jax.config.update('jax_compilation_cache_dir', str(folder))
  jax.config.update('jax_persistent_cache_min_compile_time_secs', 1.0)
  jax.config.update('jax_persistent_cache_min_entry_size_bytes', 0)
  return folder
