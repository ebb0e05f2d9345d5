"""Command-line entry points (`mvcoba-train`, `mvcoba-eval`, `mvcoba-export`, `mvcoba-viz`,
`mvcoba-demo`, `mvcoba-reproduce`): argument parsing and process set-up around the library.
They need the `train` extra; an install for deployment only (`.[deploy]`) is told so in one line."""
from __future__ import annotations

import importlib.util
import sys

LINE_LIMIT = 300  # characters of one line of an error message
LINES_LIMIT = 20  # lines of one error message (a case file's overlaps are one line each)


def fail(error) -> int:
  """Prints `error` as `error: ...` on stderr, each line and the number of lines bounded (a
  message may quote what a user gave); the exit status of a refused input, 2."""
  lines = str(error).splitlines() or ['']
  shown = [line if len(line) <= LINE_LIMIT else line[:LINE_LIMIT - 3] + '...'
           for line in lines[:LINES_LIMIT]]
  if len(lines) > LINES_LIMIT:
    shown.append(f'  ... and {len(lines) - LINES_LIMIT} more lines')
  print('error: ' + '\n'.join(shown), file=sys.stderr)
  return 2


TRAINING = ('jax', 'mujoco', 'flax', 'optax', 'orbax', 'scipy', 'tqdm')  # the train extra's
_missing = [name for name in TRAINING if importlib.util.find_spec(name) is None]
if _missing:
  sys.exit(fail(f"the commands need the train extra (missing {', '.join(_missing)}): "
                "pip install 'mvcoba-jax[train]'"))
