"""The `novel` suite, objects no training pool holds, and its validation twin.

- novel/ (shipped): 4 heaps of 8-14 of the held-out everyday objects (`sim/everyday.py`: mug,
  cup, bowl, cans, a bottle, fruit, a ball, a marker, boxes) and 4 packed arrangements of them
  (cans and boxes side by side in rows and grids, gaps under a finger's width), from NOVEL_SEED;
- val-novel/ (docs/results/validation): the same kinds of case made of the procedural validation
  set (`sim/objects/procedural-val`, drawn apart from training's), for choosing on.
Each case passes mvcoba-eval's load check; heaps are redrawn until nothing leaves the table as
they settle, as the block suites' are. The case files name the objects by paths relative to
themselves, so a suite folder evaluates from anywhere in the package.

  python -m mvcoba_jax.suites.novel
"""
from __future__ import annotations

import argparse
import os
import pathlib

import numpy as np

from mvcoba_jax import runtime
from mvcoba_jax.sim import arrangements, procedural
from mvcoba_jax.sim.scenarios import COLOR_NAMES
from mvcoba_jax.suites import SUITES_DIR
from mvcoba_jax.suites import generate

NOVEL_SEED = 70_000  # novel's draws; val-novel's are NOVEL_SEED + 5000
TWIN = 'val-novel'  # the validation twin's folder under docs/results/validation
HEAPS = (8, 10, 12, 14)  # objects of each heap case
EVERYDAY = procedural.OBJECTS / 'everyday'
VALIDATION_SET = procedural.OBJECTS / 'procedural-val'
# Flat-sided or round objects that stand side by side: the packed cases' members.
PACKABLE_EVERYDAY = ('soup_can', 'tuna_can', 'pudding_box', 'gelatin_box', 'large_marker')
PACKABLE_KINDS = ('convex', 'bar')  # of the procedural validation set


def objects(folder: pathlib.Path) -> list[str]:
  """The absolute references of the objects of a set's folder, in name order."""
  return sorted(str(p) for p in folder.iterdir() if p.is_dir())


def packed(members: list[str], seed: int) -> str:
  """A case of 2-3 rows of 2-4 `members` side by side (each row one object repeated or mixed,
  drawn), gaps of `arrangements.GAP`, placed as the packed block cases are."""
  rng = np.random.default_rng(seed)
  gap, parts, y = rng.uniform(*arrangements.GAP), [], 0.0
  for _ in range(rng.integers(2, 4)):
    names = [members[i] for i in rng.integers(len(members), size=rng.integers(2, 5))]
    row, depth = arrangements.row(rng, names, y, gap, turns=False)
    parts, y = parts + row, y + depth + gap
  placed = arrangements.placed(parts, rng, generate.FAMILY_HALF)
  start = int(rng.integers(10))
  return generate.HEADER + ''.join(
      generate.line(name, COLOR_NAMES[(start + i) % 10], x, y, yaw)
      for i, (name, x, y, yaw, _) in enumerate(placed))


def suite(pool: list[str], members: list[str], seed: int) -> list[str]:
  """Heaps of `pool` objects (`HEAPS`) and 4 packed cases of `members`, each the first draw
  that passes the load check."""
  heaps = [generate.passing(lambda tries, n=n, i=i: generate.heap_on_table(
      n, seed + 100 * tries + i, pool=tuple(pool), isolated=False)) for i, n in enumerate(HEAPS)]
  rows = [generate.passing(lambda tries, i=i: packed(members, seed + 50 + 100 * tries + i))
          for i in range(4)]
  return heaps + rows


def suites() -> dict[pathlib.Path, list[str]]:
  """Folder -> the text of each of its case files (references absolute until written)."""
  everyday = objects(EVERYDAY)
  validation = objects(VALIDATION_SET)
  return {
      SUITES_DIR / 'novel': suite(everyday, [o for o in everyday
                                             if pathlib.Path(o).name in PACKABLE_EVERYDAY],
                                  NOVEL_SEED),
      generate.VALIDATION_DIR / TWIN: suite(
          validation, [o for o in validation if pathlib.Path(o).name.split('_', 1)[1]
                       in PACKABLE_KINDS], NOVEL_SEED + 5000),
  }


def write(folder: pathlib.Path, texts: list[str]) -> None:
  """Each case as `folder/NAME-NN.scn`, its objects' paths made relative to the folder."""
  folder.mkdir(parents=True, exist_ok=True)
  relative = os.path.relpath(procedural.OBJECTS, folder)
  for i, text in enumerate(texts):
    path = folder / f'{folder.name}-{i:02d}.scn'
    path.write_text(text.replace(str(procedural.OBJECTS), relative).replace(
        'mvcoba_jax.suites.generate', 'mvcoba_jax.suites.novel'))
    print(path)


def main(argv=None) -> None:
  argparse.ArgumentParser(description=__doc__.split('\n\n')[0]).parse_args(argv)
  runtime.setup()
  for folder, texts in suites().items():
    write(folder, texts)


if __name__ == '__main__':
  main()
