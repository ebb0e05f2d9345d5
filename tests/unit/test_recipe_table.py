"""The recipe study's table (experiments/recipe_table.py) from evaluation folders."""
import dataclasses
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / 'experiments'))
import recipe_table  # noqa: E402
from tests.helpers import logged_row  # noqa: E402

R = recipe_table.BASE  # the reproduction's preset, where a tie goes


def _evaluation(folder: pathlib.Path, suite: str, successes: list[int]):
  """A finished evaluation of one policy: per case, one run of 4 grasps of 3 objects."""
  folder.mkdir(parents=True)
  (folder / 'results.json').write_text(json.dumps({suite: {'mvcoba': logged_row(successes)}}))
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
  choose = recipe_table.choose
  assert choose({R: [80, 80], 'authors': [83, 84], 'paper_text': [70, 70]}) == 'authors'
  assert choose({R: [80, 80], 'authors': [82, 83.8], 'paper_text': [70, 70]}) == R
  assert choose({R: [90, 90], 'authors': [85, 85], 'paper_text': [95, 95]}) == 'paper_text'


def test_a_preset_that_cannot_win_is_ruled_out_and_its_missing_seed_not_needed():
  """At 100 on its missing seed authors reaches (90 + 100) / 2 = 95 < 93 + 3: ruled out, and the
  choice is made without it; paper_text at 100 could still reach 85 > default + 3 = 83."""
  decided = {R: [93, 93], 'authors': [90], 'paper_text': [50, 50]}
  assert recipe_table.ruled_out(decided) == {'authors', 'paper_text'}
  assert recipe_table.choose(decided) == R
  open_ = {R: [80, 80], 'authors': [70, 70], 'paper_text': [70]}
  assert recipe_table.ruled_out(open_) == {'authors'}
  assert recipe_table.choose(open_) is None
  assert recipe_table.ruled_out({R: [95]}) == set()  # nothing is known of the others


def test_each_seed_is_scored_over_the_suites(tmp_path):
  """A seed's score is its grasp success averaged over the suites' cases, then the suites."""
  for preset, successes in ((R, [4, 2]), ('authors', [4, 4])):
    for seed in (0, 1):
      _evaluation(tmp_path / 'eval' / f'{recipe_table.SCREEN[preset]}-vpg-s{seed}', '/t/val-random', successes)
  _evaluation(tmp_path / 'eval' / 'preset_default-s0', '/t/val-random', [4])  # MV-COBA
  _evaluation(tmp_path / 'eval' / 'preset_paper_text-s0', '/t/val-ordered', [2])
  assert recipe_table.screen_scores(tmp_path) == {
      'mvcoba': {R: [100.0], 'paper_text': [50.0]},
      'vpg': {R: [75.0, 75.0], 'authors': [100.0, 100.0]}}


def test_the_reproduction_trains_each_method_with_the_landed_screens_choice():
  """RECIPES follows the screen in docs/results/recipe/baselines: the chosen preset for every
  method the screen has decided, the default for the rest."""
  from mvcoba_jax.reproduction import RECIPES
  scores = recipe_table.screen_scores(ROOT / 'docs' / 'results' / 'recipe' / 'baselines')
  assert RECIPES == {m: recipe_table.choose(scores.get(m, {})) or R for m in RECIPES}


def test_the_reproduction_trains_a_method_its_recipe_at_the_papers_actions():
  """`reproduction.trained_for`: a method named in the recipes gets that preset, the others the
  command's config, all at the reproduction's action count."""
  from mvcoba_jax.config import resolve
  from mvcoba_jax.reproduction import trained_for
  configs = trained_for('test', resolve(R), {'vpg': 'authors'}, ['mvcoba', 'vpg'], 3000)
  assert configs['vpg'] == dataclasses.replace(resolve('authors'), train=dataclasses.replace(
      resolve('authors').train, total_actions=3000))
  assert configs['mvcoba'].env.occluded_share == 0.25 and configs['vpg'].env.occluded_share == 0
  assert configs['mvcoba'].train.total_actions == 3000
