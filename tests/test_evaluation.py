"""Evaluation end to end on the tiny preset: cases loaded, run, scored; vmapped == one by one."""
import json

import cv2
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import eval as eval_cli
from envs.scenarios import case_to_layout, read_case, stack_layouts
from envs.tabletop import Tabletop
from mvcoba_jax import evaluation, metrics, viz
from mvcoba_jax.config import resolve

CASES = {
    'pair.scn': 'cube red 0.05 0.0 0\nflat_box blue -0.1 0.1 30\n',
    'three.scn': 'cube green -0.05 -0.05 0\ncube yellow 0.1 0.1 45\nflat_box pink 0.0 0.12 0\n',
}
MAX_ACTIONS = 3


@pytest.fixture(scope='module')
def setup(tmp_path_factory):
  folder = tmp_path_factory.mktemp('suite')
  for name, text in CASES.items():
    (folder / name).write_text(text)
  config = resolve('configs/tiny.py')
  cases = [read_case(folder / name) for name in CASES]
  env = Tabletop(eval_cli.suite_config(config, eval_cli.pool_for(cases)))
  policy = evaluation.heuristic_policy(config.env.num_rotations)
  run = jax.jit(lambda l, k: evaluation.evaluate(env, policy, (0, 1), l, k, MAX_ACTIONS))
  layouts = stack_layouts([case_to_layout(c, env) for c in cases])
  keys = jax.random.split(jax.random.PRNGKey(0), len(cases))
  return folder, env, run, layouts, keys, run(layouts, keys)


def test_cases_are_run_and_scored(setup):
  _, _, _, _, _, runs = setup
  logs = evaluation.run_logs(runs)
  assert [r.objects for r in logs] == [2, 3]
  for r in logs:
    assert 1 <= r.actions <= MAX_ACTIONS
    assert r.grasp_successes <= r.grasp_attempts <= r.actions
    assert r.picked == r.grasp_successes and r.picked <= r.objects
    assert r.completed == (r.picked == r.objects)
  m = metrics.case_metrics(logs)
  assert 0.0 <= m['grasp_success'] <= 100.0 and m['runs'] == 2


def test_vmapped_evaluation_equals_cases_one_by_one(setup):
  """Each case alone, its batch filled with copies of itself, gives what it gave beside others.

  Alone means one case's data in the same compiled program: XLA's programs for different batch
  sizes round differently (3.7e-5 m apart after settling here), and a grasp on a knife edge can
  flip; within one program the batch entries cannot influence each other.
  """
  _, _, run, layouts, keys, together = setup
  n = len(CASES)
  for i in range(n):
    alone = run(jax.tree.map(lambda x: jnp.stack([x[i]] * n), layouts), jnp.stack([keys[i]] * n))
    for a, b in zip(jax.tree.leaves(alone), jax.tree.leaves(together)):
      assert (np.asarray(a) == np.asarray(b)[i]).all()


def test_suite_pool_smaller_than_the_training_drops_is_fine():
  config = eval_cli.suite_config(resolve('configs/default.py'), (('cube', 2),))
  assert Tabletop(config).num_slots == 2 and config.env.num_objects == 2


def test_malformed_case_fails_with_file_and_line_before_compiling(tmp_path, capsys):
  bad = tmp_path / 'bad.scn'
  bad.write_text('cube red 0.0 0.0 0\ncube red zero 0.0 0\n')
  code = eval_cli.main(['--baseline', 'heuristic', '--suite', str(bad), '--config',
                        'configs/tiny.py', '--out', str(tmp_path / 'out')])
  assert code == 2
  err = capsys.readouterr().err
  assert 'bad.scn:2' in err and "'x'" in err


def test_eval_cli_writes_tables_and_visuals(setup, tmp_path, capsys):
  folder = setup[0]
  code = eval_cli.main(['--baseline', 'heuristic', '--suite', str(folder), '--config',
                        'configs/tiny.py', '--runs', '1', '--max-actions', str(MAX_ACTIONS),
                        '--out', str(tmp_path / 'out'), '--save-visuals'])
  assert code == 0
  assert '/2 runs finished' in capsys.readouterr().err  # progress from inside the jitted loop
  text = (tmp_path / 'out' / 'results.md').read_text()
  assert 'grasp success' in text and 'pair' in text and 'baseline:heuristic' in text
  report = json.loads((tmp_path / 'out' / 'results.json').read_text())
  row = report[str(folder)]['baseline:heuristic']
  actions = row['cases']['pair']['actions']
  (run,) = row['runs']['pair']
  assert run['actions'] == actions and run['objects'] == 2
  assert run['picked'] + run['lost'] <= run['objects']
  strips = sorted((tmp_path / 'out' / 'visuals' / folder.name / 'baseline_heuristic').glob('*.png'))
  assert [p.name for p in strips] == ['pair_run0.png', 'three_run0.png']
  image = cv2.imread(str(strips[0]))
  side = image.shape[0] // 2  # two views stacked, each a square heightmap scaled up
  assert image.shape[1] == actions * (side + 4) - 4


def test_run_strip_draws_each_action_where_it_was_taken():
  """A grasp that lifted at a known cell is a green bar there; a failed one is red; a push is an
  arrow pointing along its direction."""
  config = resolve('configs/tiny.py')
  r, scale = 56, 3
  steps = lambda *v: np.array([v])
  trace = evaluation.Trace(
      color=np.zeros((1, 3, 2, r, r, 3), np.uint8), primitive=steps(1, 1, 0),
      rotation=steps(0, 0, 0), row=steps(10, 30, 40), col=steps(20, 30, 10),
      grasp_success=steps(True, False, False), active=steps(True, True, True))
  image = viz.run_strip(trace, 0, config, scale=scale)
  width = r * scale
  assert image.shape == (2 * width, 3 * width + 2 * 4, 3)
  frame = lambda t, view: image[view * width:(view + 1) * width,
                                t * (width + 4):t * (width + 4) + width]
  for view in (0, 1):
    assert (frame(0, view)[10 * scale + 1, 20 * scale + 1] == viz.GRASP_OK_COLOR).all()
    assert (frame(1, view)[30 * scale + 1, 30 * scale + 1] == viz.GRASP_FAILED_COLOR).all()
    push = np.all(frame(2, view) == viz.PUSH_COLOR, axis=-1)
    rows, cols = np.nonzero(push)
    assert cols.min() >= 10 * scale - 5 and cols.max() > 20 * scale  # rotation 0 points to +x
    assert np.ptp(rows) < 4 * scale
  assert not np.any(np.all(frame(0, 0) == viz.GRASP_FAILED_COLOR, axis=-1))
