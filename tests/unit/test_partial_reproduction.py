"""The part of a running reproduction that can land (experiments/partial_reproduction.py)."""
import json
import pathlib
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / 'experiments'))
import partial_reproduction  # noqa: E402
from mvcoba_jax.evaluation.report import ResultsError  # noqa: E402
from tests.helpers import logged_row  # noqa: E402


def test_only_suites_with_every_row_land(tmp_path):
  """random holds both seeds of two methods; ordered only one row so far: it is left out."""
  rows = {f'{m} ({m}-s{s})': logged_row([4 - s, 3]) for m in ('mvcoba', 'vpg') for s in (0, 1)}
  (tmp_path / 'results.json').write_text(json.dumps(
      {'random': rows, 'ordered': {'mvcoba (mvcoba-s0)': logged_row([4])}}))
  text = partial_reproduction.finished_part(str(tmp_path), rows=4)
  assert '### random' in text and 'ordered' not in text
  # seed 0: (100 + 75) / 2, seed 1: (75 + 75) / 2 -> 81.25 over both
  assert '| MV-COBA (mvcoba) | 2 | 81.2 [' in text and '87.5 / 75.0 |' in text
  with pytest.raises(ResultsError, match=r'no suite has all 5 rows yet \(random 4, ordered 1\)'):
    partial_reproduction.finished_part(str(tmp_path), rows=5)
