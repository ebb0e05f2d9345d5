"""The Python API as a user meets it: examples/python_api.py trains, evaluates, plots and loads
through `mvcoba_jax.*`; its policy exported with the figures its evaluation measured."""
import contextlib
import importlib.util
import io
import json
import pathlib

import pytest

from mvcoba_jax import export, policy

ROOT = pathlib.Path(__file__).resolve().parents[2]
# jax2onnx's GroupNorm plugin reads Variable.value, which Flax deprecates.
pytestmark = pytest.mark.filterwarnings('ignore::DeprecationWarning:jax2onnx')


@pytest.fixture(scope='module')
def example(tmp_path_factory):
  """(the example's folder, what it printed): the example run once for this module."""
  spec = importlib.util.spec_from_file_location('python_api', ROOT / 'examples' / 'python_api.py')
  module = importlib.util.module_from_spec(spec)
  spec.loader.exec_module(module)
  folder = tmp_path_factory.mktemp('python_api')
  printed = io.StringIO()
  with contextlib.redirect_stdout(printed):
    assert module.main(['--workdir', str(folder), '--actions', '8']) == 0
  return folder, printed.getvalue()


def test_python_api_example_trains_evaluates_plots_and_loads(example):
  folder, printed = example
  assert 'trained 8 actions' in printed and 'loaded mvcoba at action 8' in printed
  rows = json.loads((folder / 'eval' / 'results.json').read_text())['occluded']
  assert list(rows) == ['mvcoba'] and rows['mvcoba']['settings']['step'] == 8
  assert (folder / 'training.png').stat().st_size > 1000


def test_export_carries_the_figures_measured_for_its_parameters(example, tmp_path):
  """model.json names the seed and commit and holds the evaluation's figures of these very
  parameters; a results file that never evaluated them is refused before anything is written."""
  folder, _ = example
  results = folder / 'eval' / 'results.json'
  row = json.loads(results.read_text())['occluded']['mvcoba']
  paths = export.export(folder / 'train', tmp_path / 'out', [results], commit='5f3edc9')
  model = json.loads(paths['model_json'].read_text())
  assert model['source']['commit'] == '5f3edc9' and model['source']['seed'] == 0
  assert model['source']['checkpoint_step'] == 8
  figure = model['figures']['frozen']['occluded']
  assert figure['grasp_success'] == row['mean']['grasp_success']
  assert figure['runs_per_case'] == 2 and figure['cases'] == len(row['settings']['cases'])
  assert figure['set'] == []  # measured as the policy trained
  assert policy.load(tmp_path / 'out')[2] == 8
  under = json.loads(results.read_text())
  under['occluded']['mvcoba']['settings']['set'] = ['env.push_length=0.05']
  (tmp_path / 'under.json').write_text(json.dumps(under))
  paths = export.export(folder / 'train', tmp_path / 'under', [tmp_path / 'under.json'])
  assert json.loads(paths['model_json'].read_text())['figures']['frozen']['occluded']['set'] == [
      'env.push_length=0.05']
  with pytest.raises(policy.PolicyError, match=r'measured again .*--set \[\]'):
    export.export(folder / 'train', tmp_path / 'both', [results, tmp_path / 'under.json'])

  other = json.loads(results.read_text())
  other['occluded']['mvcoba']['settings']['params'] = '0' * 16
  stranger = tmp_path / 'other.json'
  stranger.write_text(json.dumps(other))
  with pytest.raises(policy.PolicyError, match='no row evaluated these parameters') as error:
    export.export(folder / 'train', tmp_path / 'refused', [stranger])
  assert str(stranger) in str(error.value) and not (tmp_path / 'refused').exists()
