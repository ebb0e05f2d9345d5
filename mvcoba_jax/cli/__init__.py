"""Command-line entry points (`mvcoba-train`, `mvcoba-eval`, `mvcoba-export`, `mvcoba-viz`,
`mvcoba-demo`, `mvcoba-reproduce`): argument parsing and process set-up around the library."""
from __future__ import annotations

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
