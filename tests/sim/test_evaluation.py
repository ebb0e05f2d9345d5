"""Evaluation end to end on the tiny preset: cases loaded, run, scored; vmapped == one by one."""
import dataclasses
import json
import pathlib

import cv2
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mvcoba_jax import methods, perception, video, viz
from mvcoba_jax.evaluation import metrics, runner
from mvcoba_jax.evaluation.protocols import ONLINE
from mvcoba_jax.evaluation.sources import Source
from mvcoba_jax.cli import eval as eval_cli
from mvcoba_jax.config import resolve
from mvcoba_jax.learner import agent
from mvcoba_jax.sim.scenarios import case_slots, case_to_layout, read_case, stack_layouts
from mvcoba_jax.learner.task import Task
from mvcoba_jax.sim.tabletop import Tabletop
from mvcoba_jax.suites import SUITES_DIR
from mvcoba_jax.suites import cases as suite_cases

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
  cases = [read_case(folder / name) for name in CASES]
  config = suite_cases.suite_config(resolve('tiny'), suite_cases.pool_for(cases))
  task = Task.build(config, (0, 1))
  policy = runner.heuristic_actor(config.env.num_rotations)
  run = lambda l, k: runner.evaluate(task, policy, l, k, MAX_ACTIONS)
  layouts = stack_layouts([case_to_layout(c, task.env) for c in cases])
  keys = jax.random.split(jax.random.PRNGKey(0), len(cases))
  return folder, task, run, layouts, keys, run(layouts, keys), config


def test_cases_are_run_and_scored(setup):
  _, task, _, _, _, runs, _ = setup
  logs = runner.run_logs(runs, task)
  assert [r.objects for r in logs] == [2, 3]
  for r in logs:
    assert 1 <= r.actions <= MAX_ACTIONS
    assert r.grasp_successes <= r.grasp_attempts <= r.actions
    assert r.picked == r.grasp_successes and r.picked <= r.objects
    assert r.completed == (r.picked == r.objects)
  m = metrics.case_metrics(logs)
  assert 0.0 <= m['grasp_success'] <= 100.0 and m['runs'] == 2


def test_each_shape_counts_its_objects_and_the_actions_aimed_at_it(setup):
  """The heuristic grasps at the highest point, an object's top: every grasp is counted against
  a shape, each lifted object against its own; the counts sum to the run's (run_log checks)."""
  _, task, _, _, _, runs, _ = setup
  logs = runner.run_logs(runs, task)
  assert [{s: c['objects'] for s, c in r.shapes.items()} for r in logs] == [
      {'cube': 1, 'flat_box': 1}, {'cube': 2, 'flat_box': 1}]
  for r in logs:
    assert metrics.run_log(dataclasses.asdict(r), 'run') == r
    assert metrics.NO_OBJECT not in r.shapes or not r.shapes[metrics.NO_OBJECT]['grasps']
    assert all(c['picked'] <= c['lifted'] for c in r.shapes.values())
  by_shape = metrics.shape_metrics(logs)
  assert sum(m['grasps'] for m in by_shape.values()) == sum(r.grasp_attempts for r in logs)
  broken = dataclasses.asdict(logs[0])
  broken['shapes']['cube']['objects'] += 1
  with pytest.raises(ValueError, match='objects sum to 3, the run counts 2'):
    metrics.run_log(broken, 'run')


def test_object_at_finds_the_object_under_a_point_as_it_lies(setup):
  """`Tabletop.object_at` in the pair case: the cube's top; the flat box (10 x 5 cm, turned 30
  degrees) along its length and across, in its own frame; the table beside it."""
  _, task, _, layouts, keys, _, _ = setup
  env = task.env
  pair = jax.tree.map(lambda x: x[:1], layouts)
  state = jax.tree.map(lambda x: x[0], jax.jit(lambda l, k: suite_cases.start(env, l, k)[0])(
      pair, keys[:1]))
  cube, box = case_slots(read_case(setup[0] / 'pair.scn'), env)
  at = jax.jit(env.object_at)
  c, s = np.cos(np.radians(30)), np.sin(np.radians(30))
  assert int(at(state, (0.05, 0.0, 0.05))) == cube
  for along, across, expect in ((0.045, 0.0, box), (0.06, 0.0, -1), (0.0, 0.02, box),
                                (0.0, 0.035, -1)):
    point = (-0.1 + along * c - across * s, 0.1 + along * s + across * c, 0.025)
    assert int(at(state, point)) == expect, (along, across)


def test_a_task_of_equal_settings_runs_the_programs_compiled_for_the_first(setup):
  """Tasks are values: one built again from an equal config equals the first, and the compiled
  start of a batch (`runner.begin`, the task a static argument) serves it without compiling."""
  _, task, _, layouts, keys, _, config = setup
  again = Task.build(dataclasses.replace(config), (0, 1))
  assert again == task and hash(again) == hash(task) and again is not task
  assert Task.build(config, (0,)) != task
  runner.begin(task, layouts, keys, MAX_ACTIONS, False)
  compiled = runner.begin._cache_size()
  runner.begin(again, layouts, keys, MAX_ACTIONS, False)
  assert runner.begin._cache_size() == compiled


def test_vmapped_evaluation_equals_cases_one_by_one(setup):
  """Each case alone, its batch filled with copies of itself, gives what it gave beside others.

  Alone means one case's data in the same compiled program: XLA's programs for different batch
  sizes round differently (3.7e-5 m apart after settling here), and a grasp on a knife edge can
  flip; within one program the batch entries cannot influence each other.
  """
  _, _, run, layouts, keys, together, _ = setup
  n = len(CASES)
  for i in range(n):
    alone = run(jax.tree.map(lambda x: jnp.stack([x[i]] * n), layouts), jnp.stack([keys[i]] * n))
    for a, b in zip(jax.tree.leaves(alone), jax.tree.leaves(together)):
      assert (np.asarray(a) == np.asarray(b)[i]).all()


@pytest.fixture
def one_and_three(setup, tmp_path):
  """Layouts of a lone cube (the heuristic clears it in one or two actions) and of `three`."""
  _, task, _, layouts, _, _, _ = setup
  (tmp_path / 'one.scn').write_text('cube red 0.05 0.0 0\n')
  return (case_to_layout(read_case(tmp_path / 'one.scn'), task.env),
          jax.tree.map(lambda x: x[1], layouts))


def test_a_run_that_finished_early_leaves_the_others_as_they_were_alone(setup, one_and_three):
  """A finished run steps on with its table emptied (cheaper); the batch's other runs do not
  notice."""
  _, task, run, _, keys, _, _ = setup
  one, three = one_and_three
  together = run(stack_layouts([one, three]), keys)
  alone = run(jax.tree.map(lambda x: jnp.stack([x] * 2), three), jnp.stack([keys[1]] * 2))
  first, second = runner.run_logs(together, task)
  assert first.completed and first.actions < second.actions == MAX_ACTIONS
  for a, b in zip(jax.tree.leaves(alone), jax.tree.leaves(together)):
    assert (np.asarray(a)[1] == np.asarray(b)[1]).all()


def test_runs_moved_to_a_smaller_batch_end_as_in_the_whole_batch(setup, one_and_three):
  """Two of four runs finish early; the runs still going move to a batch of two. With
  the heuristic (no network, nothing that rounds by batch size) every counter and every counted
  step of the trace is what the whole batch gives."""
  task = setup[1]
  one, three = one_and_three
  four = stack_layouts([one, one, one, three])
  keys = jax.random.split(jax.random.PRNGKey(3), 4)
  policy = runner.heuristic_actor(task.env.config.env.num_rotations)
  run = lambda smallest: runner.evaluate(task, policy, four, keys, MAX_ACTIONS, record=True,
                                         smallest=smallest)
  whole, moved = run(smallest=4), run(smallest=1)
  assert sum(r.actions < MAX_ACTIONS for r in runner.run_logs(moved, task)) >= 2
  for a, b in zip(jax.tree.leaves(whole.replace(trace=None)),
                  jax.tree.leaves(moved.replace(trace=None))):
    assert (np.asarray(a) == np.asarray(b)).all()
  active = np.asarray(whole.trace.active)  # what a finished run did after is not kept
  assert (active == np.asarray(moved.trace.active)).all()
  for a, b in zip(jax.tree.leaves(whole.trace), jax.tree.leaves(moved.trace)):
    assert (np.asarray(a)[active] == np.asarray(b)[active]).all()


def test_suite_pool_smaller_than_the_training_drops_is_fine():
  config = suite_cases.suite_config(resolve('default'), (('cube', 2),))
  assert Tabletop(config.tabletop).num_slots == 2 and config.env.num_objects == 2


def test_malformed_case_fails_with_file_and_line_before_compiling(tmp_path, capsys):
  bad = tmp_path / 'bad.scn'
  bad.write_text('cube red 0.0 0.0 0\ncube red zero 0.0 0\n')
  code = eval_cli.main(['--baseline', 'heuristic', '--suite', str(bad), '--config',
                        'tiny', '--out', str(tmp_path / 'out')])
  assert code == 2
  err = capsys.readouterr().err
  assert 'bad.scn:2' in err and "'x'" in err


def test_overlapping_case_is_refused_before_compiling_naming_both_lines(tmp_path, capsys):
  """Six 1.obj blocks at 5.7 cm pitch: arches in VPG's block table, which overlap; cubes in the
  MV-COBA authors' table, which do not."""
  grid = tmp_path / 'grid.txt'
  grid.write_text(''.join(f'1.obj 0.1 0.2 0.3 {-0.5 + 0.057 * i:.3f} {0.057 * j:.3f} 0.026 0 0 0\n'
                          for i in range(2) for j in range(3)))
  args = ['--baseline', 'heuristic', '--suite', str(grid), '--out', str(tmp_path / 'out')]
  assert eval_cli.main(args) == 2
  err = capsys.readouterr().err
  assert err.startswith('error: ') and f'{grid}:1 and line 2' in err and '--allow-bad-cases' in err
  assert 'they are likely mvcoba\'s block set' in err.splitlines()[0]  # the cause, first
  assert not (tmp_path / 'out').exists()
  assert eval_cli.main(args + ['--blocks', 'lego']) == 2
  assert "--blocks 'lego': expected [SUITE=]TABLE with TABLE one of vpg, mvcoba" in capsys.readouterr().err


def test_fit_overlaps_evaluates_an_overlapping_case_reporting_moves_and_starts(tmp_path, capsys):
  """A cube placed 6 mm into its neighbour: refused as it is, evaluated with --fit-overlaps,
  which reports the move; every run starts with the file's objects in play."""
  case = tmp_path / 'nudge.scn'
  case.write_text('cube red 0.0 0.0 0\ncube blue 0.044 0.0 0\n')
  args = ['--baseline', 'heuristic', '--suite', str(case), '--config', 'tiny', '--runs', '2',
          '--max-actions', '1', '--out', str(tmp_path / 'out')]
  assert eval_cli.main(args) == 2
  assert '--fit-overlaps moves objects' in capsys.readouterr().err
  with pytest.raises(SystemExit):
    eval_cli.main(args + ['--fit-overlaps', '0'])
  assert eval_cli.main(args + ['--fit-overlaps']) == 0
  out = capsys.readouterr().out
  assert 'moved objects in 1 of 1 cases' in out and '(lines 2: 3.0 mm)' in out
  assert 'objects in play at the start of the runs, of the file\'s: nudge 2/2' in out
  settings = json.loads((tmp_path / 'out' / 'results.json').read_text())[str(case)][
      'baseline:heuristic']['settings']
  assert settings['fitted_mm'] == {'nudge': {'max_mm': 3.0, 'mean_mm': 1.5,
                                             'lines_mm': {'2': 3.0}}}
  assert settings['listed_objects'] == {'nudge': 2} and settings['fit_overlaps_mm'] == 70.0


def test_case_that_loses_an_object_while_settling_is_refused_naming_the_line(tmp_path, capsys):
  """A cube set down over the outer edge of another at the border falls off the table as the
  case settles: refused before the policy compiles, unless --allow-bad-cases."""
  case = tmp_path / 'edge.scn'
  case.write_text('cube red 0.195 0.0 0\ncube blue 0.221 0.0 0 0.0765\ncube green 0.0 0.1 0\n')
  args = ['--baseline', 'heuristic', '--suite', str(case), '--config', 'tiny', '--runs', '1',
          '--max-actions', '1', '--out', str(tmp_path / 'out')]
  assert eval_cli.main(args) == 2
  err = capsys.readouterr().err
  assert f'{case}:2: the cube left the workspace while the case settled' in err
  assert eval_cli.main(args + ['--allow-bad-cases']) == 0


def test_load_check_holds_objects_on_the_table_not_those_set_on_the_heap():
  """In a heap, objects the file sets down on others slide centimetres onto it as it settles;
  those it puts on the table move millimetres. With a 1 mm bound the check names only the
  latter (each 'listed on the table'); with its 1 cm bound, none."""
  case = read_case(SUITES_DIR / 'dev-random' / 'dev-random-05.scn')
  config = resolve('default')
  strict = suite_cases.case_problems([case], config, settle_move=0.001)
  on_table = {o.line for o in case.objects if len(_fields(case, o.line)) == 5}
  named = {int(m.split(':')[1]) for m in strict}
  assert named and named <= on_table and all('listed on the table, moved' in m for m in strict)
  assert suite_cases.case_problems([case], config) == []


def _fields(case, line):
  return pathlib.Path(case.path).read_text().splitlines()[line - 1].split()


def test_eval_cli_writes_tables_visuals_and_videos(setup, tmp_path, capsys):
  folder = setup[0]
  code = eval_cli.main(['--baseline', 'heuristic', '--suite', str(folder), '--config',
                        'tiny', '--runs', '1', '--max-actions', str(MAX_ACTIONS),
                        '--out', str(tmp_path / 'out'), '--save-visuals', '--video'])
  assert code == 0
  captured = capsys.readouterr()
  assert '/2 runs finished' in captured.err  # progress from inside the jitted loop
  assert 'objects left the workspace' in captured.out
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
  lost = json.loads((strips[0].parent / 'losses.json').read_text())
  assert len(lost) == sum(r['lost'] for rs in row['runs'].values() for r in rs)
  image = cv2.imread(str(strips[0]))
  side = image.shape[0] // 2  # two views stacked, each a square heightmap scaled up
  assert image.shape[1] == actions * (side + 4) - 4
  # One MP4 per run: every action it took, video.FRAMES_PER_PRIMITIVE frames each, readable.
  videos = tmp_path / 'out' / 'videos' / folder.name / 'baseline_heuristic'
  assert sorted(p.name for p in videos.glob('*.mp4')) == ['pair_run0.mp4', 'three_run0.mp4']
  capture = cv2.VideoCapture(str(videos / 'pair_run0.mp4'))
  frames = []
  while (frame := capture.read())[0]:
    frames.append(frame[1])
  assert len(frames) == actions * video.FRAMES_PER_PRIMITIVE
  assert frames[0].shape == (video.CAMERA.height, video.CAMERA.width, 3)
  # The gripper moves within a primitive: its first and last frames differ.
  assert np.abs(frames[0].astype(int) - frames[video.FRAMES_PER_PRIMITIVE - 1]).mean() > 1


def test_run_strip_draws_each_action_where_it_was_taken():
  """A grasp that lifted at a known cell is a green bar there; a failed one is red; a push is an
  arrow pointing along its direction."""
  config = resolve('tiny')
  r, scale = 56, 3
  steps = lambda *v: np.array([v])
  trace = runner.Trace(
      color=np.zeros((1, 3, 2, r, r, 3), np.uint8), object_xyz=np.zeros((1, 3, 1, 3)),
      left_workspace=np.zeros((1, 3, 1), bool), primitive=steps(1, 1, 0),
      rotation=steps(0, 0, 0), row=steps(10, 30, 40), col=steps(20, 30, 10),
      grasp_success=steps(True, False, False), active=steps(True, True, True))
  image = viz.run_strip(trace, 0, Task.build(config, (0, 1)), scale=scale)
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


def _results(folder, suite, method, runs_by_case):
  """A results.json as mvcoba-eval writes it, holding only what --tables reads: the per-run counts."""
  folder.mkdir()
  runs = {case: [dict(zip(('actions', 'grasp_attempts', 'grasp_successes', 'objects', 'picked',
                            'lost', 'completed'), r)) for r in rs]
          for case, rs in runs_by_case.items()}
  (folder / 'results.json').write_text(
      json.dumps({suite: {method: {'wall_s': 10.0, 'runs': runs}}}))


def test_tables_join_evaluations_run_apart_and_score_them_again(tmp_path, capsys):
  _results(tmp_path / 'a', 'ordered', 'mvcoba', {'c0': [(4, 4, 4, 4, 4, 0, True)],
                                                 'c1': [(5, 4, 3, 3, 3, 0, True)]})
  _results(tmp_path / 'b', 'ordered', 'vpg', {'c0': [(6, 2, 1, 4, 1, 0, False)]})
  _results(tmp_path / 'c', 'ordered', 'mvcoba', {'c1': [(3, 3, 3, 3, 3, 0, True)]})
  code = eval_cli.main(['--tables', *(str(tmp_path / f) for f in 'abc'),
                        '--out', str(tmp_path / 'joined')])
  assert code == 0
  report = json.loads((tmp_path / 'joined' / 'results.json').read_text())['ordered']
  assert list(report) == ['mvcoba', 'vpg', 'mvcoba (c)']
  # mvcoba: c0 4/4 grasps in 4 actions, c1 3/4 grasps and a push: 3 objects in 5 actions
  assert report['mvcoba']['cases']['c1']['grasp_success'] == 75.0
  assert report['mvcoba']['mean']['grasp_success'] == pytest.approx(87.5)
  assert report['mvcoba']['mean']['action_efficiency'] == pytest.approx((100 + 60) / 2)
  assert report['vpg']['cases']['c0']['grasp_to_push'] == 0.5
  assert report['vpg']['mean']['completion'] == 0.0
  assert report['vpg']['mean']['objects_picked'] == 25.0  # 1 of its 4 objects
  text = (tmp_path / 'joined' / 'results.md').read_text()
  assert '| vpg | 50.0 | - | 50.0 |' in text  # vpg ran no c1: its cell is '-'
  assert '| mvcoba (c) | - | 100.0 | 100.0 |' in text
  assert text in capsys.readouterr().out
  # Beside the paper: our methods by the paper's names, its figures, its methods we did not run.
  beside = (tmp_path / 'joined' / 'comparison.md').read_text()
  assert '### ordered: mean [95% CI over 1/2 seeds] and the paper' in beside
  assert '| MV-COBA (mvcoba) | 2 |' in beside and '| VPG (vpg) | 1 |' in beside
  assert '86.3' in beside and '| MVP (not run) | - |' in beside


def test_tables_of_results_without_run_counts_fail_naming_the_file(tmp_path, capsys):
  (tmp_path / 'old').mkdir()
  (tmp_path / 'old' / 'results.json').write_text(json.dumps(
      {'random': {'mvcoba': {'cases': {}, 'mean': {}, 'wall_s': 1.0}}}))
  assert eval_cli.main(['--tables', str(tmp_path / 'old'), '--out', str(tmp_path / 'x')]) == 2
  err = capsys.readouterr().err
  assert 'old/results.json' in err and 'random/mvcoba' in err and 'per-run counts' in err
  (tmp_path / 'list').mkdir()
  (tmp_path / 'list' / 'results.json').write_text('[1, 2]')
  assert eval_cli.main(['--tables', str(tmp_path / 'list'), '--out', str(tmp_path / 'x')]) == 2
  assert 'list/results.json: not the results of mvcoba-eval' in capsys.readouterr().err


def test_losses_name_the_action_and_where_the_object_was():
  """One object leaves in run 0's second action (a push from the middle of the heightmap); a
  loss marked after the run had finished does not count."""
  config = resolve('tiny')
  steps = lambda *v: np.array([v])
  xyz = np.zeros((1, 3, 2, 3))
  xyz[0, 1, 1] = (0.2, -0.05, 0.03)
  left = np.zeros((1, 3, 2), bool)
  left[0, 1, 1] = left[0, 2, 0] = True
  r = perception.grid_size(config.perception, config.scene)
  trace = runner.Trace(
      color=np.zeros((1, 3, 2, r, r, 3), np.uint8), object_xyz=xyz, left_workspace=left,
      primitive=steps(1, 0, 1), rotation=steps(0, 0, 0), row=steps(0, r // 2, 0),
      col=steps(0, r // 2, 0), grasp_success=steps(True, False, False),
      active=steps(True, True, False))
  (record,) = runner.losses(trace, ['c_run0'], Task.build(config, (0, 1)))
  half = config.perception.heightmap_resolution / 2  # the centre of cell (r/2, r/2)
  assert record['run'] == 'c_run0' and record['action'] == 1 and record['slot'] == 1
  assert record['primitive'] == 'push' and not record['grasp_success']
  assert record['gripper_xy'] == pytest.approx([half, half], abs=1e-4)
  assert record['distance_to_gripper'] == pytest.approx(np.hypot(0.2 - half, 0.05 + half), abs=1e-4)
  assert record['margin_to_border'] == pytest.approx(config.scene.workspace_half - 0.2, abs=1e-4)


def test_tables_refuse_a_folder_given_twice_and_tell_folders_of_one_name_apart(tmp_path, capsys):
  for parent in 'xy':
    (tmp_path / parent).mkdir()
    _results(tmp_path / parent / 'eval', 'ordered', 'mvcoba', {'c0': [(4, 4, 4, 4, 4, 0, True)]})
  a, b = str(tmp_path / 'x' / 'eval'), str(tmp_path / 'y' / 'eval')
  assert eval_cli.main(['--tables', a, a, '--out', str(tmp_path / 'j')]) == 2
  assert 'given twice' in capsys.readouterr().err
  assert eval_cli.main(['--tables', a, b, '--out', str(tmp_path / 'j')]) == 0
  rows = json.loads((tmp_path / 'j' / 'results.json').read_text())['ordered']
  assert list(rows) == ['mvcoba', 'mvcoba (y/eval)']


def test_repeated_failed_actions_are_counted_per_run(setup):
  """A policy that grasps at one bare corner every time fails the same way until the failure
  rule ends the run: every action after the first repeats a failed action with nothing changed
  in between. The heuristic, whose rotation is drawn anew, repeats nothing exactly here."""
  _, task, _, layouts, keys, heuristic, config = setup
  zeros = lambda obs: jnp.zeros(obs.depth.shape[0], jnp.int32)
  stubborn = runner.Frozen(lambda obs, changed, keys, failed: agent.PixelAction(
      primitive=zeros(obs) + agent.GRASP, rotation=zeros(obs), row=zeros(obs), col=zeros(obs)))
  runs = runner.evaluate(task, stubborn, layouts, keys, 10)
  logs = runner.run_logs(runs, task)
  attempts = config.env.max_failures + 1
  assert [r.actions for r in logs] == [attempts] * 2
  assert [r.repeated_failures for r in logs] == [attempts - 1] * 2
  assert metrics.case_metrics(logs)['repeated_failures'] == attempts - 1
  assert all(r.repeated_failures == 0 for r in runner.run_logs(heuristic, task))


@pytest.fixture(scope='module')
def online(setup):
  """An untrained network's online policy on the setup's cases."""
  from flax import nnx

  from mvcoba_jax.learner import networks
  _, task, _, layouts, keys, _, config = setup
  model = networks.build_network(config.network, config.env.num_rotations, nnx.Rngs(0))
  policy = Source('mvcoba', config, model).actor(config, ONLINE)
  run = lambda l, k, cap: runner.evaluate(task, policy, l, k, cap)
  return policy, run, layouts, keys


def test_online_runs_learn_each_from_its_own_transitions(online):
  """Each run starts from the trained parameters and ends with its own: two cases end apart;
  a case alone (its batch filled with copies of itself) ends with what it ended with beside the
  other, weights and counters alike."""
  policy, run, layouts, keys = online
  together = run(layouts, keys, 4)
  leaves = [np.asarray(x) for x in jax.tree.leaves(together.carry.params)]
  start = [np.asarray(x) for x in jax.tree.leaves(policy.params)]
  for i in range(2):
    assert any(not np.array_equal(x[i], s) for x, s in zip(leaves, start))
  assert any(not np.array_equal(x[0], x[1]) for x in leaves)
  for i in range(2):
    alone = run(jax.tree.map(lambda x: jnp.stack([x[i]] * 2), layouts), jnp.stack([keys[i]] * 2), 4)
    for a, b in zip(jax.tree.leaves(alone), jax.tree.leaves(together)):
      np.testing.assert_array_equal(np.asarray(a)[0], np.asarray(b)[i])


def test_a_finished_run_learns_no_more(online, setup):
  """A run on an empty table finishes with its first action, which has no next state to learn
  from: it ends with the trained weights, whether the batch stops at 3 actions or 6; the other
  run, still going at 3, learned more by 6."""
  policy, run, layouts, keys = online
  task = setup[1]
  empty = layouts.replace(in_play=layouts.in_play.at[0].set(False))
  short, long = run(empty, keys, 3), run(empty, keys, 6)
  assert [r.actions for r in runner.run_logs(short, task)] == [1, 3]
  params = lambda runs, i: [np.asarray(x)[i] for x in jax.tree.leaves(runs.carry.params)]
  start = [np.asarray(x) for x in jax.tree.leaves(policy.params)]
  for runs in (short, long):
    assert all(np.array_equal(a, b) for a, b in zip(params(runs, 0), start))
  assert any(not np.array_equal(a, b) for a, b in zip(params(short, 1), params(long, 1)))


def test_no_repeat_takes_the_next_best_action_instead_of_a_failed_one(setup):
  """Maps that score the bare corner cells best, in order: the greedy policy grasps at the same
  cell until the failure rule ends the run; with `no_repeat` it moves on to the next best cell
  after each failure, repeating none."""
  _, task, _, layouts, keys, _, config = setup
  r = perception.grid_size(config.perception, config.scene)
  ramp = -jnp.arange(r * r, dtype=jnp.float32).reshape(r, r)
  q_maps = lambda obs: jnp.broadcast_to(ramp, (obs.depth.shape[0], 2, 1, r, r))
  logs = {}
  for no_repeat in (False, True):
    policy = runner.greedy_actor(q_maps, agent.Decision.of(methods.get('grasp_only'), config),
                                 no_repeat)
    logs[no_repeat] = runner.run_logs(runner.evaluate(task, policy, layouts, keys, 10), task)
  attempts = config.env.max_failures + 1
  assert [(g.actions, g.repeated_failures) for g in logs[False]] == [(attempts, attempts - 1)] * 2
  assert [(g.actions, g.repeated_failures) for g in logs[True]] == [(attempts, 0)] * 2


def test_sigkill_during_an_evaluation_loses_at_most_the_row_in_progress(setup, tmp_path):
  """An evaluation killed after its first row was written keeps that row: --resume afterwards
  evaluates only the rest and ends with the rows of an evaluation never interrupted."""
  import subprocess
  import sys
  import time
  folder = setup[0]
  (tmp_path / 'second').mkdir()
  (tmp_path / 'second' / 'one.scn').write_text('cube red 0.05 0.0 0\n')
  args = ['--baseline', 'heuristic', '--suite', str(folder), str(tmp_path / 'second'),
          '--config', 'tiny', '--runs', '1', '--max-actions', str(MAX_ACTIONS)]
  assert eval_cli.main([*args, '--out', str(tmp_path / 'whole')]) == 0
  killed = tmp_path / 'killed'
  process = subprocess.Popen([sys.executable, '-m', 'mvcoba_jax.cli.eval', *args, '--out',
                              str(killed)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
  deadline = time.monotonic() + 600
  while process.poll() is None and time.monotonic() < deadline:
    if (killed / 'results.json').is_file():
      process.kill()
      break
    time.sleep(0.05)
  process.wait()
  rows = json.loads((killed / 'results.json').read_text())
  assert list(rows) == [str(folder)]  # the first row only: killed before the second was written
  assert eval_cli.main([*args, '--out', str(killed), '--resume']) == 0
  whole = json.loads((tmp_path / 'whole' / 'results.json').read_text())
  resumed = json.loads((killed / 'results.json').read_text())
  strip = lambda report: {s: {m: r['runs'] for m, r in rows.items()} for s, rows in report.items()}
  assert strip(resumed) == strip(whole)


def test_evaluate_and_join_as_library_calls(setup, tmp_path):
  """`mvcoba_jax.evaluate` is mvcoba-eval as a function: it returns the report it writes;
  `join_evaluations` scores it again from its runs; bad input raises EvaluationError."""
  import mvcoba_jax
  from mvcoba_jax import api
  folder = setup[0]
  report = mvcoba_jax.evaluate(suites=[str(folder)], baseline='heuristic', config='tiny',
                               runs=1, max_actions=MAX_ACTIONS, out=tmp_path / 'o',
                               progress=False)
  row = report[str(folder)]['baseline:heuristic']
  assert runner.advance._cache_size() == 0  # the row's programs released, not kept for good
  assert set(row['cases']) == {'pair', 'three'} and row['settings']['protocol'] == 'frozen'
  assert json.loads((tmp_path / 'o' / 'results.json').read_text())[str(folder)][
      'baseline:heuristic']['runs'] == row['runs']
  joined = api.join_evaluations([tmp_path / 'o'], tmp_path / 'j')
  assert joined[str(folder)]['baseline:heuristic']['cases']['pair']['grasp_success'] == \
      row['cases']['pair']['grasp_success']
  with pytest.raises(api.EvaluationError, match='a baseline has none'):
    mvcoba_jax.evaluate(suites=[str(folder)], baseline='heuristic', protocol='online')
  # Another suite resumed into the same folder: the first suite's row stays.
  (tmp_path / 'b').mkdir()
  (tmp_path / 'b' / 'one.scn').write_text('cube red 0.05 0.0 0\n')
  mvcoba_jax.evaluate(suites=[str(tmp_path / 'b')], baseline='heuristic', config='tiny', runs=1,
                      max_actions=MAX_ACTIONS, out=tmp_path / 'o', resume=True, progress=False)
  both = json.loads((tmp_path / 'o' / 'results.json').read_text())
  assert list(both) == [str(tmp_path / 'b'), str(folder)]
  assert both[str(folder)]['baseline:heuristic']['runs'] == row['runs']


def test_videos_where_a_file_stands_are_refused_before_any_run(setup, tmp_path, capsys):
  out = tmp_path / 'out'
  out.mkdir()
  (out / 'videos').write_text('not a folder')
  assert eval_cli.main(['--baseline', 'heuristic', '--suite', str(setup[0]), '--config', 'tiny',
                        '--runs', '1', '--out', str(out), '--resume', '--video']) == 2
  assert 'videos is a file, where the runs\' pictures go' in capsys.readouterr().err
  assert not (out / 'results.json').exists()
