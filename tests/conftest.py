"""Shared test setup: the persistent compilation cache and the preset loader."""
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # configs/ and the packages, also without an editable install

from mvcoba_jax.runtime import enable_compilation_cache  # noqa: E402

enable_compilation_cache()
