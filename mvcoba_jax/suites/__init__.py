"""The shipped suites (package data) and how a suite name becomes its case files.

The sealed test suites (`SEALED`: heaps, packed arrangements of the types training draws and of
three types it never draws, held-out occluders) and `isolated` are ours (`.scn`, written by
`generate.py` from seeds nothing else used; `manifest.json` records them); `vpg` is VPG's eleven
hard cases in VPG's text format, copied under its BSD license (`vpg/`). The development suites
(`DEVELOPMENT`) are the test suites of every result before the sealed ones: they chose recipes,
so they serve choosing now, as validation does. A sealed suite is run once per claim, every method
of the comparison at once, and no figure from it feeds a choice (docs/results/sealed.md). `novel`
holds objects no training pool holds (`novel.py`, docs/objects.md) and is run the same way; its
validation twin, `val-novel`, is for choosing.
"""
from __future__ import annotations

import pathlib

from mvcoba_jax.sim.scenarios import ScenarioError

SUITES_DIR = pathlib.Path(__file__).resolve().parent
SEALED = ('random', 'ordered', 'packed-ring', 'packed-t_shape', 'packed-stack', 'occluded')
DEVELOPMENT = ('dev-random', 'dev-ordered', 'dev-occluded')
CLAIM = SEALED + ('vpg',)  # what a claim runs, once: the sealed suites and VPG's public cases
NOVEL = 'novel'  # the held-out everyday objects
SUITES = SEALED + ('isolated', 'vpg', NOVEL) + DEVELOPMENT  # every shipped suite


def suite_files(names: list[str]) -> dict[str, list[pathlib.Path]]:
  """Suite name -> its case files; `all` is every sealed suite, `isolated` and `vpg`; a PATH (a
  case file, or a folder of .scn and .txt files) is a suite of its own."""
  if 'all' in names:
    names = [n for n in names if n != 'all'] + list(SEALED) + ['isolated', 'vpg']
  out = {}
  for name in dict.fromkeys(names):
    if not name.isprintable():  # it heads a table and keys the results: one line of text
      raise ScenarioError(f'suite {name!r}: a name or path without line breaks or control '
                          'characters expected')
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
