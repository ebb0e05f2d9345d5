"""The recipe study's table (experiments/recipe_table.py) from evaluation folders."""
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / 'experiments'))
import recipe_table  # noqa: E402


def _evaluation(folder: pathlib.Path, suite: str, successes: list[int]):
  """A finished evaluation of one policy: per case, one run of 4 grasps of 3 objects."""
  run = lambda s: {'actions': 4, 'grasp_attempts': 4, 'grasp_successes': s, 'objects': 3,
                   'picked': min(s, 3), 'lost': 0, 'completed': s >= 3, 'repeated_failures': 0}
  runs = {f'case-{i:02d}': [run(s)] for i, s in enumerate(successes)}
  folder.mkdir(parents=True)
  (folder / 'results.json').write_text(json.dumps({suite: {'mvcoba': {'runs': runs}}}))
  (folder / 'done').write_text('')


def test_seeds_evaluated_from_two_checkouts_meet_in_one_row(tmp_path):
  """A study resumed from another worktree names the same suite by another path; the variant's
  seeds are still one row, averaged with their interval (not the last seed alone)."""
  _evaluation(tmp_path / 'eval' / 'heap-s0', '/tree-a/val-random', [4, 3])
  _evaluation(tmp_path / 'eval' / 'heap-s1', '/tree-b/val-random', [2, 1])
  (tmp_path / 'study.jsonl').write_text('')
  lines = recipe_table.table(tmp_path, ('grasp_success',)).splitlines()
  assert lines[0].startswith('| variant | seeds | val-random: grasp success |')
  # seed 0: 100 and 75 -> 87.5; seed 1: 50 and 25 -> 37.5; both: 62.5
  assert lines[2].startswith('| heap | 2 | 62.5 [') and len(lines) == 3
