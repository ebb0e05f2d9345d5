"""The comparison of a running `mvcoba-reproduce`'s suites whose every row has finished: the part
of a long reproduction that can land before the whole (its evaluation keeps each finished
policy x suite row in results.json as it goes).

    python experiments/partial_reproduction.py TABLES_DIR --rows 30 > partial.md
"""
import argparse
import sys

from mvcoba_jax.evaluation import paper, report


def finished_part(tables: str, rows: int) -> str:
  """Markdown of the suites of TABLES/results.json that hold `rows` rows: `paper.comparisons` and
  `paper.summary`. report.ResultsError when none does yet or the file cannot be read."""
  results = report.joined_report([tables])
  finished = {suite: held for suite, held in results.items() if len(held) == rows}
  if not finished:
    raise report.ResultsError(f'{tables}: no suite has all {rows} rows yet ('
                              + ', '.join(f'{s} {len(r)}' for s, r in results.items()) + ')')
  return f'{paper.comparisons(finished)}\n\n{paper.summary(finished, suites=tuple(finished))}'


def main() -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('tables', help="the reproduction's --out folder (or its online/)")
  parser.add_argument('--rows', type=int, required=True,
                      help='rows of a finished suite: methods x seeds')
  args = parser.parse_args()
  try:
    print(finished_part(args.tables, args.rows))
  except report.ResultsError as e:
    sys.exit(f'partial_reproduction: {e}')
  return 0


if __name__ == '__main__':
  sys.exit(main())
