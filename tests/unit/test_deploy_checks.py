"""The checks around a policy's network (deploy/checks.py): what may reach it, what may leave it."""
import math

import numpy as np
import pytest

from mvcoba_jax.deploy import checks
from mvcoba_jax.sim.contract import push_length

SIDE, TOP, HALF = 8, 0.4, 0.224


def obs(views=2, depth=0.05, color=0.5):
  return (np.full((views, SIDE, SIDE, 3), color, np.float32),
          np.full((views, SIDE, SIDE), depth, np.float32))


def test_a_sound_observation_passes_scaled_and_with_unseen_cells_zeroed():
  color, depth = obs()
  depth[0, 0, 0], color[1, 2, 2, 1] = np.nan, np.inf
  c, d = checks.observation(color, depth, 2, SIDE, TOP)
  assert d[0, 0, 0] == 0.0 and c[1, 2, 2, 1] == 0.0 and d.dtype == c.dtype == np.float32
  c8, _ = checks.observation(np.full((2, SIDE, SIDE, 3), 255, np.uint8), obs()[1], 2, SIDE, TOP)
  c16, _ = checks.observation(np.full((2, SIDE, SIDE, 3), 65535, np.uint16), obs()[1], 2, SIDE,
                              TOP)
  assert c8.max() == c16.max() == 1.0
  _, d = checks.observation(*obs(depth=-0.004), 2, SIDE, TOP)
  assert d.min() == 0.0  # a few mm below the table is the table


@pytest.mark.parametrize('what, color, depth, match', [
    ('millimetres', *obs(depth=50.0), 'millimetres'),
    ('below the table', *obs(depth=-0.02), 'below'),
    ('one view', *obs(views=1), r'the policy takes \(2, 8, 8\)'),
    ('colour 0-255 floats', *obs(color=200.0), '0..1'),
    ('negative colour', *obs(color=-0.5), '0..1'),
    ('blind camera', obs()[0], np.full((2, SIDE, SIDE), np.nan), 'view 0: its depth'),
    ('blind colour', np.full((2, SIDE, SIDE, 3), np.nan), obs()[1], 'view 0: its colour'),
    ('int32 colour', obs()[0].astype(np.int32), obs()[1], 'dtype int32'),
    ('object depth', obs()[0], np.array([None] * 4), 'dtype object'),
])
def test_a_broken_observation_is_refused_in_one_line(what, color, depth, match):
  with pytest.raises(checks.Refused, match=match) as e:
    checks.observation(color, depth, 2, SIDE, TOP)
  assert '\n' not in str(e.value), what


@pytest.mark.parametrize('q, angle, position, match', [
    (math.nan, 0.0, (0.0, 0.0, 0.05), 'non-finite'),
    (math.inf, 0.0, (0.0, 0.0, 0.05), 'non-finite'),
    (1.0, math.nan, (0.0, 0.0, 0.05), 'angle'),
    (1.0, 0.0, (0.3, 0.0, 0.05), 'leaves the workspace'),
    (1.0, 0.0, (0.0, -0.3, 0.05), 'leaves the workspace'),
    (1.0, 0.0, (0.0, 0.0, -0.01), 'leaves the workspace'),
    (1.0, 0.0, (0.0, 0.0, 30.0), 'leaves the workspace'),
    (1.0, 0.0, (0.0, math.nan, 0.05), 'leaves the workspace'),
])
def test_an_unsafe_action_is_refused(q, angle, position, match):
  with pytest.raises(checks.Refused, match=match):
    checks.action(q, angle, position, HALF, TOP)
  checks.action(1.0, 0.5, (0.2, -0.2, 0.1), HALF, TOP)  # a sound one passes


def test_a_push_is_cut_short_at_the_workspace_edge():
  assert push_length((0.0, 0.0), 0.3, 0.1, HALF) == 0.1  # well inside: as trained
  assert math.isclose(push_length((HALF - 0.04, 0.0), 0.0, 0.1, HALF), 0.04)
  assert math.isclose(push_length((0.0, -HALF + 0.03), -math.pi / 2, 0.1, HALF), 0.03)
  corner = push_length((HALF - 0.02, HALF - 0.05), math.pi / 4, 0.1, HALF)
  assert math.isclose(corner, 0.02 * math.sqrt(2))  # the nearer edge along the diagonal
  assert push_length((HALF - 0.01, 0.0), math.pi, 0.1, HALF) == 0.1  # inwards: as trained
  for angle in np.linspace(-math.pi, math.pi, 17):  # wherever it starts, it ends inside
    length = push_length((HALF - 0.005, -HALF + 0.005), angle, 0.1, HALF)
    end = (HALF - 0.005 + length * math.cos(angle), -HALF + 0.005 + length * math.sin(angle))
    assert 0 <= length <= 0.1 and max(abs(v) for v in end) <= HALF + 1e-12


def test_the_simulator_cuts_a_push_by_the_same_rule():
  """One push contract: jitted over JAX arrays (as `sim.primitives.target` calls it) the rule
  gives the robot's lengths, to float32's precision."""
  import jax  # noqa: PLC0415 (the deploy checks themselves need no JAX)
  import jax.numpy as jnp  # noqa: PLC0415
  rng = np.random.default_rng(0)
  starts = rng.uniform(-HALF, HALF, (64, 2))
  angles = rng.uniform(-math.pi, math.pi, 64)
  cut = jax.jit(jax.vmap(lambda s, a: push_length((s[0], s[1]), a, 0.1, HALF, xp=jnp)))
  simulated = np.asarray(cut(jnp.asarray(starts, jnp.float32), jnp.asarray(angles, jnp.float32)))
  robot = [push_length(tuple(s), a, 0.1, HALF) for s, a in zip(starts, angles)]
  np.testing.assert_allclose(simulated, robot, atol=1e-6)
  assert (simulated < 0.1 - 1e-3).sum() >= 10  # some of them cut


def test_one_change_rule_and_one_failure_count_for_simulator_and_robot():
  """`observed_change` and `failures_after` give the simulator's values (jitted over JAX arrays,
  as `Task` calls them) and the robot's (numpy, Python's bools) alike, for every input; and the
  count is of failed actions in a row, pushes that changed nothing included: after a failed
  grasp and such a push, a policy allowed one retry no longer lets the frames decide."""
  import itertools  # noqa: PLC0415

  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415

  from mvcoba_jax.sim.contract import failures_after, observed_change  # noqa: PLC0415
  rows = np.array(list(itertools.product([0, 1], [0, 1], [0, 1], range(4))))
  for keeps, retries in itertools.product([True, False], range(3)):
    def both(frames, grasp, held, failures, xp):
      changed, rule = observed_change(frames, grasp, held, failures, keeps, retries, xp)
      return changed, rule, failures_after(failures, grasp, held, changed, xp)
    simulated = jax.jit(lambda r: both(r[:, 0] > 0, r[:, 1] > 0, r[:, 2] > 0, r[:, 3], jnp))(
        jnp.asarray(rows))
    robot = [both(bool(f), bool(g), bool(h), int(n), np) for f, g, h, n in rows]
    for i, values in enumerate(zip(*robot)):
      np.testing.assert_array_equal(np.asarray(simulated[i]), np.asarray(values, int))
  failures, seen = 0, []
  for frames, grasp, held in ((True, True, False), (False, False, False), (True, True, False)):
    _, rule = observed_change(frames, grasp, held, failures, False, 1)
    changed, _ = observed_change(frames, grasp, held, failures, False, 1)
    failures = failures_after(failures, grasp, held, changed)
    seen.append((bool(rule), int(failures)))
  assert seen == [(True, 1), (False, 2), (False, 3)]


SHIPPED = __import__('pathlib').Path(__file__).resolve().parents[2] / 'pretrained'
ODD = [None, 'x', -1, 2 ** 70, 1e300, True, [], {}, [[1]], 0.5]
FIELDS = ('format', 'primitives.push', 'primitives.grasp',
          'rotations.num_rotations', 'rotations.angles_rad', 'heightmap.resolution_m',
          'heightmap.workspace_half_m', 'heightmap.grid_size', 'heightmap.num_views',
          'heightmap.views_used', 'onnx.file', 'config.perception.change_min',
          'config.perception.change_max', 'config.perception.change_area',
          'config.perception.heightmap_resolution', 'config.env.push_length')


def test_every_shipped_model_json_reads():
  from mvcoba_jax.deploy import model_file
  for folder in sorted(p for p in SHIPPED.iterdir() if p.is_dir()):
    spec = model_file.read(folder)
    assert spec.grid_size == 112 and len(spec.angles_rad) == 16
    assert (folder / spec.onnx_file).resolve().parent == folder.resolve()


def test_a_model_json_broken_where_an_action_depends_on_it_is_refused_naming_it(tmp_path):
  """Each field an action reads, dropped or set to each odd value in turn (fixed list): the file
  reads only where the value is still one the field allows, else one line naming the file and
  the field; an unknown format, NaN, and an ONNX file outside the folder are refused."""
  import json
  import random
  from mvcoba_jax.deploy import DeployError, model_file
  base = json.loads((SHIPPED / 'mvcoba' / 'model.json').read_text())
  rng, refused, read = random.Random(0), 0, 0

  def write(described, text=None):
    (tmp_path / 'model.json').write_text(text or json.dumps(described))
    return tmp_path

  for dotted in FIELDS:
    for value in [...] + rng.sample(ODD, 5):
      described = json.loads(json.dumps(base))
      *parents, key = dotted.split('.')
      section = described
      for name in parents:
        section = section[name]
      if value is ...:
        del section[key]
      else:
        section[key] = value
      try:
        model_file.read(write(described))
        read += 1
        assert value is not ... and (dotted.startswith(('config.perception.change',
                                                        'config.env.push_length'))
                                     or (dotted, value) == ('onnx.file', 'x')), (dotted, value)
      except DeployError as e:
        refused += 1
        assert str(tmp_path / 'model.json') in str(e) and '\n' not in str(e), str(e)
        assert dotted in str(e) or 'format' in str(e), (dotted, str(e))
  assert refused >= 75 and read <= 6, (refused, read)
  for change, match in ((('format', 'mvcoba-jax-export/3'), 'format'),
                        (('onnx', {'file': '../other/model.onnx'}), 'outside')):
    described = json.loads(json.dumps(base))
    described[change[0]] = change[1]
    with pytest.raises(DeployError, match=match):
      model_file.read(write(described))
  text = json.dumps(base).replace('"angles_rad": [0.0', '"angles_rad": [NaN', 1)
  with pytest.raises(DeployError, match='NaN is not a number JSON allows'):
    model_file.read(write(None, text))


def test_an_export_whose_graph_leaves_the_rule_out_loads_its_parameters_but_cannot_act(tmp_path):
  """Format 1 (the graph stopped at the maps): its parameters still read, and deploy refuses to
  act on its graph, naming the command that exports it again."""
  import json
  from mvcoba_jax.deploy import DeployError, OnnxPolicy, model_file
  described = json.loads((SHIPPED / 'mvcoba' / 'model.json').read_text())
  assert described['format'] == model_file.FORMAT
  described['format'] = 'mvcoba-jax-export/1'
  (tmp_path / 'model.json').write_text(json.dumps(described))
  assert not model_file.read(tmp_path).graph_decides
  pytest.importorskip('onnxruntime')
  with pytest.raises(DeployError, match='leaves the action rule to the runtime; export it again'):
    OnnxPolicy(tmp_path)


def test_the_robot_loop_refuses_a_negative_count_before_loading(capsys):
  import importlib.util
  spec = importlib.util.spec_from_file_location('robot_loop', SHIPPED.parent / 'examples' /
                                                'robot_loop.py')
  loop = importlib.util.module_from_spec(spec)
  spec.loader.exec_module(loop)
  with pytest.raises(SystemExit) as e:
    loop.main(['--model', 'nowhere', '--actions', '-1'])
  assert e.value.code == 2 and 'at least 1 action' in capsys.readouterr().err


def test_a_runtime_may_act_under_another_rule_after_a_failed_grasp_within_its_range(tmp_path,
                                                                                     capsys):
  """`model_file.acting_rule` (OnnxPolicy's keywords, the robot loop's flag): the retries after a
  failed grasp replaced, as `mvcoba-eval --set` evaluates them; a count out of 0-100, not whole,
  or set where a failed grasp is change anyway is refused in one line, before the network loads,
  and so is a model.json holding such a pair."""
  import importlib.util
  import json
  from mvcoba_jax.deploy import DeployError, model_file
  shipped = model_file.read(SHIPPED / 'mvcoba')
  assert not shipped.failed_grasp_changes and shipped.failed_grasp_retries == 0
  assert model_file.acting_rule(shipped, failed_grasp_retries=1).failed_grasp_retries == 1
  assert model_file.acting_rule(shipped) == shipped
  for retries, match in ((-1, 'whole number in 0-100'), (101, 'whole number in 0-100'),
                         (1.0, 'whole number'), (True, 'whole number')):
    with pytest.raises(DeployError, match=match):
      model_file.acting_rule(shipped, failed_grasp_retries=retries)
  with pytest.raises(DeployError, match='needs failed_grasp_changes false'):
    model_file.acting_rule(shipped, failed_grasp_changes=True, failed_grasp_retries=2)
  described = json.loads((SHIPPED / 'mvcoba' / 'model.json').read_text())
  described['config']['perception'].update(failed_grasp_changes=True, failed_grasp_retries=2)
  (tmp_path / 'model.json').write_text(json.dumps(described))
  with pytest.raises(DeployError, match='model.json: config.perception: failed_grasp_retries 2'):
    model_file.read(tmp_path)
  pytest.importorskip('onnxruntime')
  spec = importlib.util.spec_from_file_location('robot_loop', SHIPPED.parent / 'examples' /
                                                'robot_loop.py')
  loop = importlib.util.module_from_spec(spec)
  spec.loader.exec_module(loop)
  assert loop.main(['--model', str(SHIPPED / 'mvcoba'), '--failed-grasp-retries', '101']) == 2
  assert 'failed_grasp_retries 101: a whole number in 0-100' in capsys.readouterr().err
