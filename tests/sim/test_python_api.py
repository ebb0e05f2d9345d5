"""The Python API as a user meets it: examples/python_api.py trains, evaluates, plots and loads
through `mvcoba_jax.*`."""
import importlib.util
import json
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_python_api_example_trains_evaluates_plots_and_loads(tmp_path, capsys):
  spec = importlib.util.spec_from_file_location('python_api', ROOT / 'examples' / 'python_api.py')
  example = importlib.util.module_from_spec(spec)
  spec.loader.exec_module(example)
  assert example.main(['--workdir', str(tmp_path), '--actions', '8']) == 0
  printed = capsys.readouterr().out
  assert 'trained 8 actions' in printed and 'loaded mvcoba at action 8' in printed
  rows = json.loads((tmp_path / 'eval' / 'results.json').read_text())['occluded']
  assert list(rows) == ['mvcoba'] and rows['mvcoba']['settings']['step'] == 8
  assert (tmp_path / 'training.png').stat().st_size > 1000
