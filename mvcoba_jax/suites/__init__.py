"""The shipped test suites (package data) and how a suite name becomes its case files.

`random`, `ordered`, `occluded` and `isolated` are ours (`.scn`, written by `generate.py`); `vpg`
is VPG's eleven hard cases in VPG's text format, copied under its BSD license (`vpg/`).
"""
from __future__ import annotations

import pathlib

from mvcoba_jax.sim.scenarios import ScenarioError

SUITES_DIR = pathlib.Path(__file__).resolve().parent
SUITES = ('random', 'ordered', 'occluded', 'isolated', 'vpg')


def suite_files(names: list[str]) -> dict[str, list[pathlib.Path]]:
  """Suite name -> its case files; `all` is every shipped suite; a PATH (a case file, or a folder
  of .scn and .txt files) is a suite of its own."""
  if 'all' in names:
    names = [n for n in names if n != 'all'] + list(SUITES)
  out = {}
  for name in dict.fromkeys(names):
    if name in SUITES:
      files = sorted((SUITES_DIR / name).glob('*.txt' if name == 'vpg' else '*.scn'))
    else:
      path = pathlib.Path(name)
      files = sorted(p for p in path.iterdir() if p.suffix in ('.scn', '.txt')) \
          if path.is_dir() else [path]
    if not files or not all(f.is_file() for f in files):
      raise ScenarioError(f'suite {name!r}: no case files found')
    out[name] = files
  return out
