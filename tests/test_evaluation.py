"""Evaluation end to end on the tiny preset: cases loaded, run, scored; vmapped == one by one."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import eval as eval_cli
from envs.scenarios import case_to_layout, read_case, stack_layouts
from envs.tabletop import Tabletop
from mvcoba_jax import evaluation, metrics
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


def test_eval_cli_writes_tables(setup, tmp_path, capsys):
  folder = setup[0]
  code = eval_cli.main(['--baseline', 'heuristic', '--suite', str(folder), '--config',
                        'configs/tiny.py', '--runs', '1', '--max-actions', str(MAX_ACTIONS),
                        '--out', str(tmp_path / 'out')])
  assert code == 0
  text = (tmp_path / 'out' / 'results.md').read_text()
  assert 'grasp success' in text and 'pair' in text and 'baseline:heuristic' in text
