"""`runtime.setup()`, which every entry point and conftest.py call: serial BLAS, the cache."""
import pathlib

import jax
import scipy
import threadpoolctl

from mvcoba_jax import runtime


def test_scipy_blas_is_serial_after_setup():
  """OpenBLAS's own threads fought XLA's for the cores (docs/design.md). Other BLAS copies
  (OpenCV bundles one) play no part in the physics."""
  scipy_libs = pathlib.Path(scipy.__file__).parent.parent / 'scipy.libs'
  blas = [lib for lib in threadpoolctl.threadpool_info()
          if pathlib.Path(lib['filepath']).parent == scipy_libs]
  assert blas, f'scipy\'s BLAS not found loaded from {scipy_libs}'
  assert all(lib['num_threads'] == 1 for lib in blas), blas


def test_compilation_cache_folder(tmp_path, monkeypatch):
  assert jax.config.jax_compilation_cache_dir == str(runtime.default_cache())  # conftest's setup
  monkeypatch.setenv('MVCOBA_JAX_CACHE', str(tmp_path / 'env'))
  assert runtime.default_cache() == tmp_path / 'env'
  monkeypatch.delenv('MVCOBA_JAX_CACHE')
  monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path / 'xdg'))
  assert runtime.default_cache() == tmp_path / 'xdg' / 'mvcoba-jax' / 'jax'
