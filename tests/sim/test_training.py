"""The jitted training step, the learner, and mvcoba-train end to end on the tiny preset."""
import json
import pathlib
import shutil
import signal
import subprocess
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mvcoba_jax
from mvcoba_jax.cli import eval as eval_cli
from mvcoba_jax.cli import reproduce as reproduce_cli
from mvcoba_jax.cli import train as train_cli
from mvcoba_jax.config import resolve
from mvcoba_jax.learner import agent, networks
from mvcoba_jax.learner import replay as replay_lib
from mvcoba_jax.learner.checkpoint import Checkpoints
from mvcoba_jax.learner.training import Trainer, course_fingerprint

TINY = 'tiny'
ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope='module')
def trainer():
  return Trainer(resolve(TINY))


@pytest.fixture(scope='module')
def iterate(trainer):
  return jax.jit(trainer.iterate)


@pytest.fixture(scope='module')
def trained(trainer, iterate):
  """The state after two host iterations of real training (8 actions)."""
  state = jax.jit(trainer.init)(jax.random.PRNGKey(0))
  logs = []
  for _ in range(2):
    state, log = iterate(state, jnp.bool_(True), jnp.float32(-1.0))
    logs.append(log)
  return state, logs


def test_one_step_program_called_k_times_trains_as_the_k_step_program(trainer, iterate):
  """`compiled(per_step=True)`, MJX's form on a CPU, takes the course of one program of K."""
  state = jax.jit(trainer.init)(jax.random.PRNGKey(0))
  args = (jnp.bool_(True), jnp.float32(-1.0))
  whole, log_whole = iterate(state, *args)
  per, log_per = trainer.compiled(per_step=True)(state, *args)
  k = trainer.config.train.steps_per_iteration
  assert np.asarray(log_per.primitive).shape == (k, trainer.config.num_envs)
  for name in ('primitive', 'grasp_success', 'changed', 'reward', 'done', 'explored'):
    np.testing.assert_array_equal(getattr(log_per, name), getattr(log_whole, name), err_msg=name)
  np.testing.assert_allclose(log_per.loss, log_whole.loss, rtol=1e-4)
  assert int(per.actions) == int(whole.actions) and int(per.updates) == int(whole.updates)
  assert int(per.replay.size) == int(whole.replay.size) > 0
  for a, b in zip(jax.tree.leaves(per.params), jax.tree.leaves(whole.params)):
    np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-6)


def test_physics_traced_into_the_program_compiles_one_step_on_a_cpu(trainer):
  mjx = Trainer(resolve(TINY, ['scene.backend=mjx']))
  assert mjx.per_step and not trainer.per_step  # the tiny preset runs native physics


def test_training_steps_fill_the_replay_and_update(trainer, trained):
  state, logs = trained
  b, k = trainer.config.num_envs, trainer.config.train.steps_per_iteration
  assert int(state.actions) == 2 * b * k
  # The default target ('acting') stores a step's transitions with the next step, once its
  # acting forward has valued their next states: the last step's still wait, and the first step
  # had nothing to learn from.
  assert int(state.replay.size) == 2 * b * k - b and bool(state.pending_valid)
  assert int(state.updates) == 2 * k - 1
  assert int(state.skipped_updates) == 0
  assert all(np.isfinite(np.asarray(log.loss)).all() for log in logs)
  assert np.asarray(state.task.env.healthy).all()


def test_warp_training_step_keeps_the_replay_ratio():
  """The whole training step on the Warp backend (physics, both cameras, the network, replay and
  updates in one compiled call), with `train.replay_ratio=1` at 4 tabletops and batches of 2:
  two updates after each lockstep action, so as many transitions are sampled as arrive."""
  config = resolve(TINY, ['scene.backend=warp', 'num_envs=4', 'train.batch_size=2',
                          'train.replay_ratio=1'])
  assert config.updates_per_step == 2
  trainer = Trainer(config)
  state = jax.jit(trainer.init)(jax.random.PRNGKey(1))
  state, log = jax.jit(trainer.iterate)(state, jnp.bool_(True), jnp.float32(-1.0))
  k = config.train.steps_per_iteration
  assert int(state.actions) == 4 * k and int(state.replay.size) == 4 * (k - 1)
  assert int(state.updates) == 2 * (k - 1) and int(state.skipped_updates) == 0
  assert np.isfinite(np.asarray(log.loss)).all() and np.asarray(state.task.env.healthy).all()
  assert np.asarray(log.primitive).size == 4 * k


def test_checkpoint_names_keep_the_task_fields_where_earlier_runs_saved_them(trained):
  """The task state (`TrainState.task`) is saved under the names its fields had at the top of
  the training state, so a run checkpointed before it existed resumes."""
  from mvcoba_jax.learner.checkpoint import _leaves
  names = set(_leaves(trained[0]))
  assert {'env.sim.qpos', 'obs.depth', 'changed', 'failures'} <= names
  assert not any(name.startswith('task.') for name in names)


def test_episode_end_bootstraps_from_the_fresh_tabletop(trainer, trained, iterate):
  """The action that ends an episode is stored with the next tabletop as s_{t+1}, not as
  terminal: the task goes on, so clearing the table is worth as much as any other success."""
  state, _ = trained
  tabletops = state.task.env
  empty = state.replace(task=state.task.replace(
      env=tabletops.replace(in_play=tabletops.in_play.at[0].set(False))))
  after, log = iterate(empty, jnp.bool_(True), jnp.float32(-1.0))
  b = trainer.config.num_envs
  # Env 0's clearing action (step 1) enters the replay at step 2, after the previous step's
  # transitions; its successor (step 2) is still pending.
  first = int(state.replay.cursor) + b
  data = after.replay.data
  assert bool(log.done[0, 0]) and not bool(log.done[1, 0])  # env 0 had nothing left: cleared
  assert not bool(data.done[first]) and bool(data.changed[first])  # grasp rule at the new tabletop
  np.testing.assert_array_equal(np.asarray(data.next_obs.depth[first]),
                                np.asarray(after.pending.obs.depth[0], np.float16))
  assert float(np.max(np.asarray(data.next_obs.depth[first], np.float32))) > 0.02  # objects again


def test_acting_target_stores_the_next_forward_and_learns_from_it():
  """train.target='acting': a step's transitions enter the replay one step later, carrying the
  rule's max Q of their next state from that step's acting forward; the update bootstraps from
  it and runs no target network."""
  trainer = Trainer(resolve(TINY, ['train.target=acting', 'train.steps_per_iteration=1']))
  step = jax.jit(trainer.iterate)
  args = (jnp.bool_(True), jnp.float32(-1.0))
  state = jax.jit(trainer.init)(jax.random.PRNGKey(0))
  first, _ = step(state, *args)
  assert int(first.replay.size) == 0 and bool(first.pending_valid)
  q = trainer.q_maps(first.params, first.task.obs)
  expected = agent.future_value(q, first.task.changed, trainer.method, trainer.config.train)
  second, _ = step(first, *args)
  b = trainer.config.num_envs
  assert int(second.replay.size) == b
  data = second.replay.data
  np.testing.assert_allclose(np.asarray(data.next_value[:b]), np.asarray(expected), rtol=1e-5,
                             atol=1e-6)
  np.testing.assert_array_equal(np.asarray(data.reward[:b]), np.asarray(first.pending.reward))
  batch = jax.tree.map(lambda x: x[:b], data)
  batch = batch.replace(obs=replay_lib._unpack(batch.obs),
                        next_obs=replay_lib._unpack(batch.next_obs))
  poisoned = jax.tree.map(lambda p: jnp.full_like(p, jnp.nan), second.target_params)
  _, td = trainer.loss(second.params, poisoned, batch, jnp.ones(b, bool))
  assert np.isfinite(np.asarray(td)).all()  # the target network played no part
  y = np.asarray(batch.reward) + trainer.config.train.gamma * np.where(
      np.asarray(batch.done), 0.0, np.asarray(batch.next_value))
  pred = networks.executed_q(trainer.q_maps(second.params, batch.obs, batch.rotation[:, None]),
                             batch.primitive, batch.row, batch.col)
  np.testing.assert_allclose(np.asarray(td), np.asarray(pred) - y, rtol=1e-5, atol=1e-5)


def test_loss_falls_on_a_fixed_replay_batch(trainer, trained):
  state, _ = trained
  key = jax.random.PRNGKey(3)
  update = jax.jit(trainer.update)
  losses = []
  for _ in range(25):
    state, loss = update(state, key)  # same key: the same sampled batch every time
    losses.append(float(loss))
  assert losses[-1] < 0.5 * losses[0], losses


def test_quarter_turns_learn_from_turned_replayed_transitions(trainer, trained):
  """`train.quarter_turns`: the update trains on quarter-turned copies of what it samples (the
  turns themselves: tests/unit/test_networks.py), so it moves the parameters elsewhere than the
  plain update from the same state and key, and its loss still falls on a fixed draw."""
  state, _ = trained
  update = jax.jit(Trainer(resolve(TINY, ['train.quarter_turns=true'])).update)
  key = jax.random.PRNGKey(3)
  plain, _ = jax.jit(trainer.update)(state, key)
  losses = []
  for i in range(25):
    state, loss = update(state, key)
    losses.append(float(loss))
    if i == 0:
      assert any(np.abs(np.asarray(a) - np.asarray(b)).max() > 1e-6
                 for a, b in zip(jax.tree.leaves(state.params), jax.tree.leaves(plain.params)))
  assert losses[-1] < 0.5 * losses[0], losses


def test_non_finite_loss_leaves_parameters_untouched(trainer, trained):
  state, _ = trained
  poisoned = state.replace(replay=state.replay.replace(
      data=state.replay.data.replace(reward=jnp.full_like(state.replay.data.reward, jnp.nan))))
  after, loss = jax.jit(trainer.update)(poisoned, jax.random.PRNGKey(0))
  assert float(loss) == 0.0
  assert int(after.skipped_updates) == int(state.skipped_updates) + 1
  for a, b in zip(jax.tree.leaves(after.params), jax.tree.leaves(state.params)):
    np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def run(workdir, *extra):
  return train_cli.main(['--config', TINY, '--workdir', str(workdir), '--eval-actions', '2', *extra])


def test_train_py_smoke_checkpoint_and_exact_resume(tmp_path):
  straight, split = tmp_path / 'straight', tmp_path / 'split'
  assert run(straight) == 0
  for name in ('config.json', 'actions.jsonl', 'metrics.jsonl', 'curves.png',
               'eval_summary.json'):
    assert (straight / name).exists(), name
  assert len((straight / 'actions.jsonl').read_text().splitlines()) == 8
  assert run(split, '--set', 'train.total_actions=4') == 0
  assert run(split, '--resume') == 0
  trainer = Trainer(resolve(TINY))
  like = jax.jit(trainer.init)(jax.random.PRNGKey(1))
  config = resolve(TINY)
  a, _ = Checkpoints(straight).restore(like, config)
  b, _ = Checkpoints(split).restore(like, config)
  assert int(a.actions) == int(b.actions) == 8
  # The restored state has the fresh state's types, so a resumed run reuses the compiled step.
  for x, y in zip(jax.tree.leaves(like), jax.tree.leaves(a)):
    assert (x.dtype, x.weak_type) == (y.dtype, y.weak_type)
  for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b)):
    np.testing.assert_array_equal(np.asarray(x), np.asarray(y))
  records = [json.loads(line) for line in (split / 'actions.jsonl').read_text().splitlines()]
  assert [r['action'] for r in records] == list(range(8))


def test_resume_with_another_network_shape_is_refused_naming_it(tmp_path, capsys):
  workdir = tmp_path / 'run'
  assert run(workdir, '--set', 'train.total_actions=4') == 0
  assert run(workdir, '--resume', '--set', 'network.features=4,8') == 2
  err = capsys.readouterr().err
  assert 'network.features=(8, 16) -> (4, 8)' in err and 'may change on resume' in err


def test_resume_without_a_checkpoint_fails_at_once_and_creates_nothing(tmp_path, capsys):
  workdir = tmp_path / 'typo'
  started = time.perf_counter()
  assert run(workdir, '--resume') == 2
  assert time.perf_counter() - started < 10 and not workdir.exists()
  assert f'{workdir / "checkpoints"} holds no checkpoint' in capsys.readouterr().err


@pytest.mark.parametrize('override, named', [('env.num_objects=99', 'env.num_objects=99'),
                                             ('scene.backend=jax', "scene.backend='jax'")])
def test_a_config_that_cannot_be_built_fails_before_the_work_directory_exists(
    tmp_path, capsys, override, named):
  workdir = tmp_path / 'run'
  with pytest.raises(SystemExit) as exit_:  # argparse's usage error
    run(workdir, '--set', override)
  assert exit_.value.code == 2
  assert not workdir.exists() and named in capsys.readouterr().err


def test_sigkill_while_writing_a_checkpoint_loses_nothing_older(tmp_path):
  """A run killed while Orbax writes checkpoint 8 resumes from checkpoint 4 and ends exactly as a
  run that was never interrupted."""
  straight, killed = tmp_path / 'straight', tmp_path / 'killed'
  extra = ['--set', 'train.total_actions=12']
  assert run(straight, *extra) == 0
  command = [sys.executable, '-m', 'mvcoba_jax.cli.train', '--config', TINY, '--workdir',
             str(killed), '--eval-actions', '2', *extra]
  process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
  folder, caught = killed / 'checkpoints', None
  deadline = time.monotonic() + 600
  while process.poll() is None and time.monotonic() < deadline and caught is None:
    names = [p.name for p in folder.iterdir()] if folder.is_dir() else []
    caught = next((n for n in names if n.startswith('8') and not n.isdigit()), None)
  process.send_signal(signal.SIGKILL)
  process.wait()
  assert caught, f'the run ended before checkpoint 8 was being written: {names}'
  assert not (folder / '8').is_dir() and (folder / '4').is_dir()
  assert run(killed, '--resume', *extra) == 0
  like = jax.jit(Trainer(resolve(TINY)).init)(jax.random.PRNGKey(1))
  config = resolve(TINY, ['train.total_actions=12'])
  a, _ = Checkpoints(straight).restore(like, config)
  b, _ = Checkpoints(killed).restore(like, config)
  assert int(a.actions) == int(b.actions) == 12
  for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b)):
    np.testing.assert_array_equal(np.asarray(x), np.asarray(y))
  records = [json.loads(line) for line in (killed / 'actions.jsonl').read_text().splitlines()]
  assert [r['action'] for r in records] == list(range(12))


def test_sweep_of_methods_and_seeds_trains_evaluates_and_aggregates(tmp_path, capsys):
  """2 methods x 2 seeds train in turn into their own folders; one evaluation of all four gives
  each method's mean and interval over its seeds."""
  sweep = tmp_path / 'sweep'
  trained = mvcoba_jax.sweep(resolve(TINY, ['train.total_actions=4']), sweep,
                             methods=['mvcoba', 'grasp_only'], seeds=[0, 1], eval_actions=1)
  assert [int(r.state.actions) for r in trained.values()] == [4] * 4
  runs = sorted(p.name for p in sweep.iterdir() if p.is_dir())
  assert runs == sorted(w.name for w in trained)
  assert runs == ['grasp_only-s0', 'grasp_only-s1', 'mvcoba-s0', 'mvcoba-s1']
  assert (sweep / 'curves-grasp_success.png').is_file()
  assert (sweep / 'curves-grasps_per_action.png').is_file()
  assert all(json.loads((sweep / r / 'config.json').read_text())['seed'] == int(r[-1])
             for r in runs)
  case = tmp_path / 'case.scn'
  case.write_text('cube red 0.0 0.0 0\nflat_box blue 0.1 0.1 0\n')
  out = tmp_path / 'eval'
  # The same run from a second folder of the same name: a row of its own, not pooled as a seed.
  shutil.copytree(sweep / 'mvcoba-s1', tmp_path / 'copy' / 'mvcoba-s1')
  assert eval_cli.main(['--checkpoint', *(str(sweep / r) for r in runs),
                        str(tmp_path / 'copy' / 'mvcoba-s1'), '--suite', str(case),
                        '--runs', '2', '--max-actions', '2', '--out', str(out)]) == 0
  rows, = json.loads((out / 'results.json').read_text()).values()
  assert 'mvcoba (sweep/mvcoba-s1)' in rows and 'mvcoba (copy/mvcoba-s1)' in rows
  assert rows['mvcoba (copy/mvcoba-s1)']['settings']['training_seed'] == 1
  text = (out / 'results.md').read_text()
  assert 'over training seeds, mean [95% t interval over the per-seed means]' in text
  assert '| mvcoba | 2 |' in text and '| grasp_only | 2 |' in text
  # The same policies under the online protocol: rows and intervals of their own, also when
  # joined with the frozen ones.
  online = tmp_path / 'online'
  assert eval_cli.main(['--checkpoint', *(str(sweep / r) for r in runs[2:]), '--suite', str(case),
                        '--runs', '1', '--max-actions', '2', '--online', '--out', str(online)]) == 0
  rows, = json.loads((online / 'results.json').read_text()).values()
  assert list(rows) == ['mvcoba (mvcoba-s0) [online]', 'mvcoba (mvcoba-s1) [online]']
  assert {r['settings']['protocol'] for r in rows.values()} == {'online'}
  assert eval_cli.main(['--tables', str(out), str(online), '--out', str(tmp_path / 'j')]) == 0
  joined = (tmp_path / 'j' / 'results.md').read_text()
  assert '| mvcoba | 2 |' in joined and '| mvcoba [online] | 2 |' in joined
  with pytest.raises(SystemExit):  # a sweep and a single run at once
    train_cli.main(['--config', TINY, '--workdir', str(sweep), '--methods', 'mvcoba',
                    '--method', 'vpg'])
  # Resumed after a stop that caught one run before its first checkpoint: the finished runs
  # are passed over and that one starts again; a run of another config is not replaced unasked.
  shutil.rmtree(sweep / 'mvcoba-s1' / 'checkpoints')
  (sweep / 'mvcoba-s1' / 'eval_summary.json').unlink()
  again = mvcoba_jax.sweep(resolve(TINY, ['train.total_actions=4']), sweep, resume=True,
                           methods=['mvcoba', 'grasp_only'], seeds=[0, 1], eval_actions=1)
  assert [w.name for w, r in again.items() if r is not None] == ['mvcoba-s1']
  assert int(again[sweep / 'mvcoba-s1'].state.actions) == 4
  assert 'stopped before its first checkpoint: starting it again' in capsys.readouterr().out
  other = sweep / 'grasp_only-s1'
  shutil.rmtree(other / 'checkpoints')
  saved = json.loads((other / 'config.json').read_text())
  (other / 'config.json').write_text(json.dumps(saved | {'train': saved['train'] | {'gamma': 0.1}}))
  with pytest.raises(mvcoba_jax.TrainError, match='grasp_only-s1 holds results of an earlier'):
    mvcoba_jax.sweep(resolve(TINY, ['train.total_actions=4']), sweep, resume=True,
                     methods=['grasp_only'], seeds=[0, 1], eval_actions=1)
  with pytest.raises(mvcoba_jax.TrainError, match='no run of the sweep in .*typo was started'):
    mvcoba_jax.sweep(resolve(TINY, ['train.total_actions=4']), tmp_path / 'typo', resume=True,
                     methods=['grasp_only'], seeds=[0, 1], eval_actions=1)


def test_reproduction_trains_evaluates_and_sets_ours_beside_the_paper(tmp_path, capsys):
  out = tmp_path / 'tables'
  assert reproduce_cli.main(['--config', TINY, '--methods', 'grasp_only', '--seeds', '0', '1',
                             '--actions', '4', '--runs', '1', '--max-actions', '2',
                             '--suites', 'occluded', '--workdir', str(tmp_path / 'sweep'),
                             '--out', str(out)]) == 0
  text = (out / 'comparison.md').read_text()
  assert text.startswith('Test protocol: the trained network, frozen')
  assert '### occluded: mean [95% CI over 2 seeds] and the paper' in text
  assert '| DRGP (grasp_only) | 2 |' in text and '| MV-COBA (not run) | - |' in text and '97.8' in text
  assert 'Expected wall time' in text and 'expected about' in capsys.readouterr().out
  assert (out / 'curves-grasp_success.png').is_file()
  online = (out / 'online' / 'comparison.md').read_text()  # the paper's test protocol
  assert online.startswith('Test protocol: every run starts from the trained network')
  assert '| DRGP (grasp_only [online]) | 2 |' in online
  # Started again it trains and evaluates nothing anew: every run is finished and every row of
  # the evaluation is kept.
  results = [json.loads((folder / 'results.json').read_text()) for folder in (out, out / 'online')]
  assert reproduce_cli.main(['--config', TINY, '--methods', 'grasp_only', '--seeds', '0', '1',
                             '--actions', '4', '--runs', '1', '--max-actions', '2',
                             '--suites', 'occluded', '--workdir', str(tmp_path / 'sweep'),
                             '--out', str(out)]) == 0
  printed = capsys.readouterr().out
  assert printed.count('finished already') == 2 and printed.count('kept from') == 4
  assert [json.loads((folder / 'results.json').read_text())
          for folder in (out, out / 'online')] == results
  # A method added later (or one not reached when a call stopped) trains beside the finished.
  assert reproduce_cli.main(['--config', TINY, '--methods', 'grasp_only', 'mvcoba', '--seeds', '0',
                             '--actions', '4', '--runs', '1', '--max-actions', '2',
                             '--suites', 'occluded', '--workdir', str(tmp_path / 'sweep'),
                             '--out', str(out), '--protocols', 'frozen']) == 0
  assert capsys.readouterr().out.count('finished already') == 1
  assert '| MV-COBA (mvcoba) | 1 |' in (out / 'comparison.md').read_text()
  # A finished run that lost its log is refused before anything is evaluated, in one line.
  (tmp_path / 'sweep' / 'grasp_only-s0' / 'metrics.jsonl').unlink()
  assert reproduce_cli.main(['--config', TINY, '--methods', 'grasp_only', '--seeds', '0',
                             '--actions', '4', '--runs', '1', '--max-actions', '2',
                             '--suites', 'occluded', '--workdir', str(tmp_path / 'sweep'),
                             '--out', str(out), '--protocols', 'frozen']) == 2
  assert 'grasp_only-s0/metrics.jsonl is missing' in capsys.readouterr().err


AUTHORS_RECIPE = ['train.failed_grasp_reward=0', 'train.no_change_push_reward=-1',
                  'train.bootstrap_no_change=false', 'train.future_max=both',
                  'train.grasp_symmetry=true', 'train.fresh_in_batch=true',
                  'train.steps_per_iteration=1', 'train.epsilon_start=1', 'train.epsilon_end=1']


def test_authors_recipe_on_real_transitions():
  """The authors' rewards and targets on transitions of real training steps (random actions):
  failed grasps earn 0 and pushes that change nothing -1, an action that changed nothing stores
  no future, the future is the max over both primitives; a grasp's loss also labels its
  rotation turned half way, and an update trains on the fresh transitions too."""
  trainer = Trainer(resolve(TINY, AUTHORS_RECIPE))
  t = trainer.config.train
  step = jax.jit(trainer.iterate)
  state = jax.jit(trainer.init)(jax.random.PRNGKey(2))
  logs = []
  for _ in range(6):
    before = state
    state, log = step(state, jnp.bool_(True), jnp.float32(-1.0))
    logs.append(jax.tree.map(lambda x: np.asarray(x)[0], log))
  b = trainer.config.num_envs
  data = jax.tree.map(lambda x: np.asarray(x)[:int(state.replay.size)], state.replay.data)
  assert len(data.reward) == 5 * b  # the sixth step's transitions are still pending
  log = jax.tree.map(lambda *x: np.concatenate(x) if np.ndim(x[0]) else np.stack(x), *logs[:5])
  np.testing.assert_array_equal(data.primitive, log.primitive)
  np.testing.assert_array_equal(data.reward, np.asarray(agent.reward(
      log.primitive, log.grasp_success, log.changed, log.lost, trainer.task.reward)))
  assert set(data.reward[log.primitive == agent.GRASP]) <= {0.0, 1.0}
  assert set(data.reward[log.primitive == agent.PUSH]) <= {-1.0, 0.5}
  np.testing.assert_array_equal(data.done, ~log.changed)  # no future where nothing changed
  assert (~log.changed).any() and log.changed.any()
  # The last stored transitions' future: the max over both maps of the step that stored them.
  q = trainer.q_maps(before.params, before.task.obs)
  np.testing.assert_allclose(data.next_value[-b:], np.asarray(q).reshape(b, -1).max(axis=1),
                             rtol=1e-5)
  # The loss: a grasp is labelled at its rotation and at that rotation turned half way.
  batch = jax.tree.map(lambda x: jnp.asarray(x[-b:]), state.replay.data)
  batch = batch.replace(obs=replay_lib._unpack(batch.obs), next_obs=replay_lib._unpack(batch.next_obs),
                        primitive=jnp.asarray([agent.GRASP, agent.PUSH]))
  valid = jnp.ones(b, bool)
  loss, _ = trainer.loss(state.params, state.target_params, batch, valid)
  k = trainer.config.env.num_rotations
  y = agent.bootstrap(batch.next_value, batch.done, batch.reward, t)
  at = lambda rotation: networks.executed_q(trainer.q_maps(state.params, batch.obs,
                                                           rotation[:, None]),
                                            batch.primitive, batch.row, batch.col)
  huber = lambda pred: networks.huber_loss(pred, y, t.huber_delta)
  turned = huber(at((batch.rotation + k // 2) % k))
  expected = jnp.sum(huber(at(batch.rotation))) + turned[0]  # the push (index 1) is not turned
  np.testing.assert_allclose(float(loss), float(expected), rtol=1e-4)
  # An update with the fresh transitions trains on the replayed batch and on them.
  key = jax.random.PRNGKey(4)
  _, sampled, _ = replay_lib.sample(state.replay, key, t.batch_size, t.priority_exponent)
  both = jax.tree.map(lambda a, c: jnp.concatenate([a, c.astype(a.dtype)]), sampled, batch)
  whole, _ = trainer.loss(state.params, state.target_params, both,
                          jnp.ones(t.batch_size + b, bool))
  _, mean_loss = jax.jit(trainer.update)(state, key, True, (batch, jnp.bool_(True)))
  np.testing.assert_allclose(float(mean_loss), float(whole) / (t.batch_size + b), rtol=1e-4)


def test_train_and_load_policy_as_library_calls(tmp_path):
  """`mvcoba_jax.train` is what mvcoba-train does, as a function; `mvcoba_jax.load_policy`
  reads back the network it trained, parameter for parameter."""
  import mvcoba_jax
  from flax import nnx
  config = resolve(TINY, ['train.total_actions=4'])
  result = mvcoba_jax.train(config, tmp_path / 'run', eval_actions=1, progress=False)
  assert int(result.state.actions) == 4 and result.summary['grasp_attempts'] >= 0
  assert {'config.json', 'actions.jsonl', 'metrics.jsonl', 'checkpoints', 'eval_summary.json',
          'curves.png', 'tensorboard'} <= {p.name for p in (tmp_path / 'run').iterdir()}
  # TensorBoard's events hold metrics.jsonl's numbers, at the same action counts.
  events = _scalars(next((tmp_path / 'run' / 'tensorboard').glob('events.out.tfevents.*')))
  lines = [json.loads(line) for line in (tmp_path / 'run' / 'metrics.jsonl').read_text().splitlines()]
  assert [step for step, _ in events['train/loss']] == [m['actions'] for m in lines]
  assert [v for _, v in events['train/loss']] == pytest.approx([m['loss'] for m in lines])
  (step, value), = events['greedy/grasp_success']
  assert step == 4 and value == pytest.approx(result.greedy['grasp_success'])
  loaded, network, step = mvcoba_jax.load_policy(tmp_path / 'run')
  assert step == 4 and loaded == config
  for a, b in zip(jax.tree.leaves(nnx.state(network)), jax.tree.leaves(result.state.params)):
    np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
  with pytest.raises(mvcoba_jax.TrainError, match='holds results of an earlier run'):
    mvcoba_jax.train(config, tmp_path / 'run', progress=False)


def _scalars(path) -> dict[str, list[tuple[int, float]]]:
  """tag -> [(step, value)] of a TensorBoard event file (TFRecord framing: length, its CRC, the
  Event proto, its CRC)."""
  import struct

  from tensorboardX.proto import event_pb2
  data, out, at = path.read_bytes(), {}, 0
  while at < len(data):
    (length,) = struct.unpack('<Q', data[at:at + 8])
    event = event_pb2.Event.FromString(data[at + 12:at + 12 + length])
    at += 12 + length + 4
    for value in event.summary.value:
      out.setdefault(value.tag, []).append((event.step, value.simple_value))
  return out


def test_a_checkpoint_the_disk_refuses_is_one_line_and_the_earlier_one_resumes(tmp_path):
  """Resumed under a file size limit (as a full disk would refuse), a run cannot write its next
  checkpoint: one error line names it and the checkpoint it can resume from, which is intact;
  a garbled action log is refused naming its line."""
  workdir = tmp_path / 'run'
  assert run(workdir, '--set', 'train.total_actions=4') == 0
  code = ('import resource, signal, sys\n'
          'signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n'
          'resource.setrlimit(resource.RLIMIT_FSIZE, (20000, 20000))\n'
          'from mvcoba_jax.cli import train\n'
          f'sys.exit(train.main(["--config", "tiny", "--workdir", {str(workdir)!r}, "--resume",'
          ' "--set", "train.total_actions=8"]))\n')
  out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, timeout=600)
  errors = [line for line in out.stderr.splitlines() if line.startswith('error: ')]
  assert out.returncode == 2 and len(errors) == 1, out.stderr[-2000:]
  assert 'cannot write checkpoint 8' in errors[0] and 'checkpoint 4 is intact' in errors[0]
  assert out.stderr.rstrip().splitlines()[-1] == errors[0]  # Orbax logs; no exception escapes
  assert Checkpoints(workdir).latest() == 4
  (workdir / 'actions.jsonl').write_text('{"action": 0}\n')
  assert run(workdir, '--resume', '--set', 'train.total_actions=8') == 2


def test_the_shipped_policy_was_trained_with_todays_numerics(trainer, iterate):
  """A fresh mvcoba-train gives pretrained/mvcoba: the tiny preset's first two calls take, bit
  for bit, the course they took at the commit that trained the shipped policy
  (`course_fingerprint`, recorded in its course.json by experiments/land_pretrained.sh). When
  training's numerics change, this fails until the shipped policy is trained again."""
  recorded = json.loads((ROOT / 'pretrained' / 'mvcoba' / 'course.json').read_text())
  got = course_fingerprint(trainer, recorded['calls'], iterate)
  assert got == recorded['fingerprint'], (
      f'the tiny course is now {got}, {recorded["fingerprint"]} when pretrained/mvcoba was '
      f'trained (at {recorded["commit"]}): training\'s numerics changed; train the shipped '
      'policy again (docs/results/pretrained-mvcoba/run.sh, experiments/land_pretrained.sh)')
