"""Two-camera ray-cast rendering, heightmaps, occlusion and change observation (tiny scene), on
both physics backends' ray casters."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mvcoba_jax import perception
from mvcoba_jax.sim.contract import changed_views
from mvcoba_jax.learner import networks
from mvcoba_jax.sim import shapes
from mvcoba_jax.sim.contract import pixel_to_world
from mvcoba_jax.sim.scenarios import case_to_layout, read_case
from tests.helpers import BACKENDS, layout, make_task, stack

CUBE, CUBE2, FLAT, FLAT2 = 0, 1, 2, 3
BOX_AT = (0.05, -0.03)  # flat box 10 x 5 x 2.5 cm, long side along x


@pytest.fixture(scope='module', params=BACKENDS)
def task(request):
  return make_task('tiny', request.param)


@pytest.fixture(scope='module')
def env(task):
  return task.env


def observer(task):
  place = jax.jit(jax.vmap(task.env.place))
  look = jax.jit(task.observe)
  return lambda layouts: look(place(stack(layouts)))


@pytest.fixture(scope='module')
def observe(task):
  return observer(task)


def cell_centres(task):
  scene = task.env.config.scene
  side = perception.grid_size(task.perception, scene)
  rows, cols = np.meshgrid(np.arange(side), np.arange(side), indexing='ij')
  return pixel_to_world(rows, cols, task.perception.heightmap_resolution, scene.workspace_half)


def scenario(tmp_path, text):
  path = tmp_path / 'case.scn'
  path.write_text(text)
  return path


def test_box_of_known_size_has_the_right_heights_cells_and_colour(task, env, observe):
  lay = layout(env, [(FLAT, *BOX_AT, 0.0)])
  lay = lay.replace(color=lay.color.at[FLAT].set(shapes.COLORS[3]))
  obs = jax.tree.map(lambda x: x[0], observe([lay]))
  res = task.perception.heightmap_resolution
  x, y = cell_centres(task)
  dx, dy = np.abs(x - BOX_AT[0]), np.abs(y - BOX_AT[1])
  inside = (dx < 0.05 - res) & (dy < 0.025 - res)  # a cell in from the edges
  outside = (dx > 0.05 + res) | (dy > 0.025 + res)  # a cell out from the edges
  for view in range(2):
    depth = np.asarray(obs.depth[view])
    seen = np.asarray(obs.seen[view])
    assert seen[inside].all(), f'view {view} misses cells on the box top'
    np.testing.assert_allclose(depth[inside], 0.025, atol=0.002)
    assert np.abs(depth[outside]).max() < 0.002, f'view {view}: height off the box'
    assert np.abs(np.asarray(obs.color[view])[inside] - shapes.COLORS[3]).max() < 1e-6
    # The table reads 0 and has the table's colour where it is seen.
    table = outside & seen
    assert table.mean() > 0.8
    assert np.abs(np.asarray(obs.color[view])[table] - 0.8).max() < 1e-6


def visible_slots(env, obs, view):
  """Object slots whose colour shows up in a view's colour heightmap over raised cells."""
  raised = np.asarray(obs.depth[view]) > 0.01
  colors = np.asarray(obs.color[view])[raised]
  return {i for i, c in enumerate(shapes.COLORS[:env.num_slots])
          if (np.abs(colors - c).max(axis=-1) < 1e-6).any()}


def test_full_occluder_hides_everything_from_camera_1_only(env, observe, tmp_path):
  case = read_case(scenario(tmp_path, 'cube blue 0.1 0.12 0\ncube green -0.1 -0.12 0\n'
                                      'occluder 0 0.3 0 0.49 0\n'))
  obs = jax.tree.map(lambda x: x[0], observe([case_to_layout(case, env)]))
  assert not np.asarray(obs.seen[0]).any(), 'camera 1 sees through the occluder'
  assert (np.asarray(obs.depth[1]) > 0.04).sum() > 20
  assert visible_slots(env, obs, 1) == {0, 1}


def test_fill_unseen_gives_a_blinded_view_what_the_other_saw(tmp_path):
  """`perception.fill_unseen`: camera 1 fully blocked, its heightmaps take camera 2's points
  (heights and colours) wherever camera 2 saw, so both cubes stand in both views; `seen` still
  says what each camera saw, and camera 2's own maps are unchanged."""
  case = read_case(scenario(tmp_path, 'cube blue 0.1 0.12 0\ncube green -0.1 -0.12 0\n'
                                      'occluder 0 0.3 0 0.49 0\n'))
  plain, filled = (jax.tree.map(lambda x: np.asarray(x[0]), observer(task)([case_to_layout(
      case, task.env)])) for task in (make_task('tiny', 'native'),
                                      make_task('tiny', 'native', 'perception.fill_unseen=true')))
  assert not filled.seen[0].any() and (filled.seen == plain.seen).all()
  seen = plain.seen[1]
  np.testing.assert_array_equal(filled.depth[0][seen], plain.depth[1][seen])
  np.testing.assert_array_equal(filled.color[0][seen], plain.color[1][seen])
  np.testing.assert_array_equal(filled.depth[1], plain.depth[1])
  assert (filled.depth[0] > 0.04).sum() > 20 and not (plain.depth[0] > 0).any()


def test_mvp_fuses_its_viewpoints_past_a_blocked_one(tmp_path):
  """MVP's four camera poses: with the first fully blocked, the fused heightmap its network reads
  still holds both cubes at their height."""
  task = make_task('tiny', 'native', 'network.method=mvp')
  env = task.env
  assert len(env.config.scene.cameras) == 4
  case = read_case(scenario(tmp_path, 'cube blue 0.1 0.12 0\ncube green -0.1 -0.12 0\n'
                                      'occluder 0 0.3 0 0.49 0\n'))
  obs = observer(task)([case_to_layout(case, env)])
  assert not np.asarray(obs.seen[0, 0]).any()
  color, depth = networks.fuse_views(obs.color, obs.depth)
  x, y = cell_centres(task)
  for cx, cy in ((0.1, 0.12), (-0.1, -0.12)):
    on_top = (np.abs(x - cx) < 0.02) & (np.abs(y - cy) < 0.02)
    np.testing.assert_allclose(np.asarray(depth[0, 0])[on_top], 0.05, atol=0.002)
  assert (np.asarray(color[0, 0]).sum(axis=-1) > 0).mean() > 0.95


def test_partial_occluders_leave_each_view_an_object_the_other_misses(env, observe, tmp_path):
  case = read_case(scenario(tmp_path, 'cube blue 0.1 0.12 0\ncube green -0.1 -0.12 0\n'
                                      'occluder 1 0.275 0.036 0.47 0\n'
                                      'occluder 2 -0.275 -0.036 0.47 0\n'))
  obs = jax.tree.map(lambda x: x[0], observe([case_to_layout(case, env)]))
  view1, view2 = visible_slots(env, obs, 0), visible_slots(env, obs, 1)
  assert view1 - view2 and view2 - view1, (view1, view2)


def test_change_observation(task, env, observe):
  cfg = task.perception
  lays = [layout(env, [(CUBE, 0.0, 0.0, 0.0), (FLAT, -0.1, 0.1, 0.0)]),
          layout(env, [(CUBE, 0.05, 0.0, 0.0), (FLAT, -0.1, 0.1, 0.0)]),  # cube moved 5 cm
          layout(env, [(FLAT, -0.1, 0.1, 0.0)])]  # cube grasped away
  obs = observe(lays)
  frame = lambda i: jax.tree.map(lambda x: x[i], obs)
  assert bool(perception.frames_changed(frame(0), frame(1), cfg))
  assert not bool(perception.frames_changed(frame(0), frame(0), cfg))
  assert bool(perception.frames_changed(frame(0), frame(2), cfg))
  # Missing cells never count: the same scene with one view blanked out changes nothing.
  blind = frame(1).replace(seen=frame(1).seen.at[0].set(False), depth=frame(1).depth.at[0].set(0))
  views = changed_views(frame(0).depth, frame(0).seen, blind.depth, blind.seen, cfg.change_min,
                        cfg.change_max, cfg.change_area, cfg.heightmap_resolution, jnp)
  assert np.asarray(views).tolist() == [False, True]


@pytest.mark.parametrize('resolution, cells', [(0.002, 300), (0.004, 75)])
def test_change_threshold_means_the_same_area_at_any_resolution(resolution, cells):
  """VPG's 300 cells at 2 mm are 75 at 4 mm: a view changed by one cell more than that area, in
  numpy (deploy) and jax.numpy (training) alike; heights moved beyond change_max do not count."""
  side = 40
  before = np.zeros((1, side, side), np.float32)
  seen = np.ones((1, side, side), bool)
  for xp in (np, jnp):
    for moved, height, want in ((cells, 0.05, False), (cells + 1, 0.05, True),
                                (cells + 1, 0.5, False)):
      after = before.copy().reshape(-1)
      after[:moved] = height
      got = changed_views(xp.asarray(before), xp.asarray(seen),
                          xp.asarray(after.reshape(1, side, side)), xp.asarray(seen),
                          0.01, 0.3, 0.0012, resolution, xp)
      assert np.asarray(got).tolist() == [want], (xp.__name__, moved, height)


def test_both_backends_see_the_same_heightmaps():
  """One scene, cast by mj_ray and by mjx.ray: the same cells seen, heights within 2 mm."""
  native, mjx = make_task('tiny', 'native'), make_task('tiny', 'mjx')
  scene = [layout(native.env, [(CUBE, 0.03, -0.02, 0.3), (FLAT, -0.08, 0.06, 0.5),
                           (CUBE2, 0.12, 0.1, 1.0), (FLAT2, -0.1, -0.15, 2.0)])]
  a, b = observer(native)(scene), observer(mjx)(scene)
  seen_a, seen_b = np.asarray(a.seen), np.asarray(b.seen)
  assert (seen_a == seen_b).mean() > 0.999
  both = seen_a & seen_b
  gap = np.abs(np.asarray(a.depth) - np.asarray(b.depth))[both]
  assert gap.max() < 0.002, np.quantile(gap, [0.5, 0.99, 1.0])
  assert (np.asarray(a.depth)[both] > 0.02).sum() > 100  # the objects are in the comparison
