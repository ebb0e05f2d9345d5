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


def test_a_preset_wins_a_method_only_by_the_tie_margin():
  assert recipe_table.choose({'default': 80.0, 'authors': 83.5, 'paper_text': 70.0}) == 'authors'
  assert recipe_table.choose({'default': 80.0, 'authors': 82.9, 'paper_text': 70.0}) == 'default'
  assert recipe_table.choose({'default': 90.0, 'authors': 85.0, 'paper_text': 95.0}) == 'paper_text'


def test_a_method_is_scored_once_both_seeds_of_every_preset_are_evaluated(tmp_path):
  """The score is grasp success over suites, seeds and cases; a method missing a seed of one
  preset is not scored (it trains the default until its screen is complete)."""
  for preset, successes in (('default', [4, 2]), ('authors', [4, 4]), ('paper_text', [2, 2])):
    for seed in (0, 1):
      _evaluation(tmp_path / 'eval' / f'preset_{preset}-vpg-s{seed}', '/t/val-random', successes)
  _evaluation(tmp_path / 'eval' / 'preset_default-s0', '/t/val-random', [4])  # MV-COBA, one seed
  assert recipe_table.screen_scores(tmp_path) == {
      'vpg': {'default': 75.0, 'authors': 100.0, 'paper_text': 50.0}}


def test_the_reproduction_trains_each_method_with_the_landed_screens_choice():
  """RECIPES follows the screen in docs/results/recipe/baselines: the chosen preset for every
  method screened in full, the default for the rest."""
  from mvcoba_jax.reproduction import RECIPES
  scores = recipe_table.screen_scores(ROOT / 'docs' / 'results' / 'recipe' / 'baselines')
  assert RECIPES == {m: recipe_table.choose(scores[m]) if m in scores else 'default'
                     for m in RECIPES}
