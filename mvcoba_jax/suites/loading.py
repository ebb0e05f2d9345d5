"""Suites as an evaluation takes them: their case files (`suite_files`) each read with its block
table, optionally fitted apart where objects interpenetrate, and load-checked
(`cases.case_problems`)."""
from __future__ import annotations

import dataclasses
import pathlib

from mvcoba_jax.config import Config
from mvcoba_jax.sim.scenarios import Case, ScenarioError, read_case
from mvcoba_jax.sim.shapes import BLOCK_TABLES
from mvcoba_jax.suites import cases as suite_cases


@dataclasses.dataclass(frozen=True)
class Suites:
  cases: dict[str, list[Case]]  # suite -> its cases, in file order
  # suite -> case -> how far fitting moved its objects (`--fit-overlaps` only)
  moves: dict[str, dict[str, dict]]
  problems: list[str]  # what the load check found, one line each
  hints: list[str]  # a block table under which the failing suites would load


def load(files_of: dict[str, list[pathlib.Path]], config: Config, blocks=(),
         fit_overlaps: float | None = None, allow_bad_cases: bool = False) -> Suites:
  """The suites of `files_of` (suite -> its case files, as `suite_files` gives them) read in
  `config`'s workspace: `blocks` ([SUITE=]TABLE
  items, `block_tables`) name the shapes of VPG-format cases; `fit_overlaps` (m) moves objects
  that interpenetrate as placed apart first (`cases.fitted`). Raises ScenarioError for a file
  or block table that cannot serve; the load check's findings are returned, not raised, with
  hints unless `allow_bad_cases`."""
  tables = block_tables(blocks, list(files_of))
  check_blocks(tables, files_of)
  table_of = {name: tables.get(name, tables.get('', 'vpg')) for name in files_of}
  bounds = config.scene.workspace_half, config.scene.workspace_top
  cases_of = {name: [read_case(f, *bounds, blocks=table_of[name]) for f in files]
              for name, files in files_of.items()}
  moves_of = {}
  if fit_overlaps is not None:
    for name, cases in cases_of.items():
      cases_of[name], moves = suite_cases.fitted(cases, config, fit_overlaps)
      moves_of[name] = {c.name: {'max_mm': round(1000 * max(m), 1),
                                 'mean_mm': round(1000 * sum(m) / len(m), 2),
                                 'lines_mm': {str(o.line): round(1000 * d, 1)
                                              for o, d in zip(c.objects, m) if d}}
                        for c, m in zip(cases, moves)}
  # Fitted objects fall onto what they were lifted from: their neighbours may shift as far.
  settle_move = max(suite_cases.SETTLE_MOVE, fit_overlaps or 0.0)
  problems = [m for cases in cases_of.values()
              for m in suite_cases.case_problems(cases, config, settle_move)]
  hints = [] if not problems or allow_bad_cases else [
      f'{name}: {hint}' for name, files in files_of.items()
      if (hint := suite_cases.other_block_table(files, config, table_of[name]))]
  return Suites(cases=cases_of, moves=moves_of, problems=problems, hints=hints)


def block_tables(given, suites: list[str]) -> dict[str, str]:
  """`[SUITE=]TABLE` items as suite ('' for every suite) -> block table, each suite named once
  and among the evaluated ones, each table a known one."""
  tables = {}
  for item in given:
    suite, _, table = item.rpartition('=')
    if table not in BLOCK_TABLES or '=' in suite:
      raise ScenarioError(f'--blocks {item[:80]!r}: expected [SUITE=]TABLE with TABLE one of '
                          f'{", ".join(BLOCK_TABLES)}')
    if suite and suite not in suites:
      raise ScenarioError(f'--blocks {item[:80]!r}: {suite[:60]!r} is not an evaluated suite '
                          f'({", ".join(suites)[:120]})')
    if suite in tables:
      raise ScenarioError(f'--blocks names {suite[:60] or "every suite"!r} twice')
    tables[suite] = table
  return tables


def check_blocks(tables: dict[str, str], files_of: dict[str, list]) -> None:
  """Refuses a block table for suites with no VPG-format (.txt) case: it would change nothing."""
  for suite in tables:
    names = [suite] if suite else list(files_of)
    if not any(pathlib.Path(f).suffix == '.txt' for n in names for f in files_of[n]):
      where = f'suite {suite[:60]} has none' if suite else 'no evaluated suite has one'
      raise ScenarioError(f'--blocks {suite + "=" if suite else ""}{tables[suite]}: block '
                          f'tables name the shapes of VPG-format (.txt) cases; {where}')
