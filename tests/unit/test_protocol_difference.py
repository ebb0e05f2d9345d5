"""The online protocol against the frozen one, paired by trained network
(experiments/protocol_difference.py)."""
import json
import pathlib
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / 'experiments'))
import protocol_difference  # noqa: E402
from mvcoba_jax.evaluation.report import METRICS  # noqa: E402


def _row(seed: int, scores: list[float], wall_s: float) -> dict:
  return {'settings': {'checkpoint': f'runs/mvcoba-s{seed}', 'step': 3008},
          'wall_s': wall_s, 'cases': {f'case-{i}': {key: s for key, _ in METRICS}
                                      for i, s in enumerate(scores)}}


def test_each_network_is_paired_with_itself_across_the_protocols():
  """Grasp success: seed 0 gains 10 points online on both cases, seed 1 20 on one and none on
  the other: 10 per seed, so no spread, whatever the seeds' own levels. Completion: seed 0 +10,
  seed 1 +10 and 0, so +5. Seed 2 only ran frozen and is left out; online took twice the
  time."""
  frozen = {'random': {'mvcoba (mvcoba-s0)': _row(0, [50, 60], 10),
                       'mvcoba (mvcoba-s1)': _row(1, [70, 80], 10),
                       'mvcoba (mvcoba-s2)': _row(2, [0, 0], 10)},
            'ordered': {'mvcoba (mvcoba-s0)': _row(0, [50], 10)}}
  online = {'random': {'mvcoba (mvcoba-s0) [online]': _row(0, [60, 70], 20),
                       'mvcoba (mvcoba-s1) [online]': _row(1, [90, 80], 20)}}
  online['random']['mvcoba (mvcoba-s1) [online]']['cases']['case-0']['completion'] = 80
  diffs = protocol_difference.differences(frozen, online)
  assert list(diffs) == ['random']  # ordered: no online rows yet
  entry = diffs['random']['mvcoba']
  assert entry['seeds'] == 2 and entry['time_ratio'] == pytest.approx(2.0)
  assert entry['grasp_success'] == pytest.approx((10.0, 10.0, 10.0))
  assert entry['completion'][0] == pytest.approx(7.5)
  text = protocol_difference.markdown(diffs)
  assert '| MV-COBA (mvcoba) | 2 | 10.0 [10.0, 10.0] | 7.5 [' in text and '| 2.00 |' in text


def test_the_command_reads_both_protocols_and_names_a_missing_file(tmp_path, monkeypatch, capsys):
  """A metric undefined in a case of either protocol (None in results.json) is shown undefined,
  not averaged over."""
  frozen = {'random': {'vpg (vpg-s0)': _row(0, [50], 10), 'vpg (vpg-s1)': _row(1, [40], 10)}}
  online = {'random': {'vpg (vpg-s0) [online]': _row(0, [60], 20),
                       'vpg (vpg-s1) [online]': _row(1, [None], 20)}}
  (tmp_path / 'results.json').write_text(json.dumps(frozen))
  monkeypatch.setattr(sys, 'argv', ['protocol_difference.py', str(tmp_path)])
  with pytest.raises(SystemExit, match=r'online/results.json: cannot read evaluation results of '
                                       r'the online protocol \(FileNotFoundError'):
    protocol_difference.main()
  (tmp_path / 'online').mkdir()
  (tmp_path / 'online' / 'results.json').write_text(json.dumps(online))
  assert protocol_difference.main() == 0
  assert '| VPG (vpg) | 2 | - | - | - | - | 2.00 |' in capsys.readouterr().out
  monkeypatch.setattr(sys, 'argv', ['protocol_difference.py', str(tmp_path), '--suites', 'ordered'])
  with pytest.raises(SystemExit, match=r"ordered: not in both protocols' results \(frozen: random"):
    protocol_difference.main()
