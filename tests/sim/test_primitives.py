"""Grasp and push on the real physics of the tiny scene (two cubes, two flat boxes), both backends.

All cases run as one batch through one compiled `step`, as training does.
"""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mvcoba_jax.sim import reserve as reserve_lib
from mvcoba_jax.sim.geometry import rotation_angle
from mvcoba_jax.sim.primitives import GRASP, PUSH
from tests.helpers import BACKENDS, actions, layout, make_env, stack

CUBE, CUBE2, FLAT, FLAT2 = 0, 1, 2, 3
YAWS = list(range(16))
PUSH_ROTATIONS = list(range(0, 16, 2))
CUBE_AT = (0.03, -0.02)
SEAM = 0.02525  # cube centres half a cube and 0.25 mm off the seam


@pytest.fixture(scope='module', params=BACKENDS)
def env(request):
  return make_env('tiny', request.param)


@pytest.fixture(scope='module')
def compiled(env):
  return jax.jit(jax.vmap(env.reset_from_case)), jax.jit(jax.vmap(env.step))


@pytest.fixture(scope='module')
def outcome(env, compiled):
  """Start states, actions and results of every scripted case, run as one batch."""
  reset, step = compiled
  layouts, rows, names = [], [], []
  for k in YAWS:  # an isolated cube grasped at every rotation
    layouts.append(layout(env, [(CUBE, *CUBE_AT, 0.0)]))
    rows.append((GRASP, k, *CUBE_AT, 0.05))
    names.append(f'grasp{k}')
  layouts.append(layout(env, [(CUBE, 0.1, 0.1, 0.0)]))  # grasp at an empty spot
  rows.append((GRASP, 0, -0.1, -0.1, 0.0))
  names.append('empty')
  # Two flat boxes end to end, 2 mm apart: the fingers, closing across the gap, land on them.
  layouts.append(layout(env, [(FLAT, -0.051, 0.0, 0.0), (FLAT2, 0.051, 0.0, 0.0)]))
  rows.append((GRASP, 4, 0.0, 0.0, 0.025))
  names.append('gap')
  for k in PUSH_ROTATIONS:  # push a cube from 5 cm behind its centre
    a = float(rotation_angle(k))
    layouts.append(layout(env, [(CUBE, 0.0, 0.0, 0.0)]))
    rows.append((PUSH, k, -0.05 * np.cos(a), -0.05 * np.sin(a), 0.05))
    names.append(f'push{k}')
  layouts.append(layout(env, [(CUBE, 0.19, 0.0, 0.0)]))  # 3.4 cm inside the border, pushed out
  rows.append((PUSH, 0, 0.14, 0.0, 0.05))
  names.append('edge')
  # Two touching cubes (0.5 mm apart along x); a grasp whose near finger lands on their seam.
  for k, y in ((0, 0.06), (8, -0.06), (0, 0.05)):
    layouts.append(layout(env, [(CUBE, -SEAM, 0.0, 0.0), (CUBE2, SEAM, 0.0, 0.0)]))
    rows.append((GRASP, k, 0.0, y, 0.05))
    names.append(f'seam{k}@{y}')
  # A row along x, 1 mm gaps: flat box, cube, cube; the middle cube pushed along +y.
  layouts.append(layout(env, [(FLAT, -0.0765, 0.0, 0.0), (CUBE, 0.0, 0.0, 0.0),
                              (CUBE2, 0.051, 0.0, 0.0)]))
  rows.append((PUSH, 4, 0.0, -0.05, 0.05))
  names.append('row')
  start = reset(stack(layouts))
  end, info = step(start, actions(rows))
  return dict(start=start, end=end, info=info, index={n: i for i, n in enumerate(names)})


def test_isolated_cube_is_lifted_at_most_rotations(env, outcome):
  info, end, idx = outcome['info'], outcome['end'], outcome['index']
  rows = [idx[f'grasp{k}'] for k in YAWS]
  success = np.asarray(info.grasp_success)[rows]
  assert success.sum() >= 14, f'grasp success per rotation: {success.astype(int)}'
  # A successful grasp removes the cube from play and counts it as picked.
  assert not np.asarray(end.in_play)[rows, CUBE][success].any()
  assert (np.asarray(end.picked)[rows][success] == 1).all()
  assert np.asarray(info.healthy)[rows].all()


def test_grasp_at_empty_spot_fails(outcome):
  i = outcome['index']['empty']
  assert not bool(outcome['info'].grasp_success[i])
  assert int(outcome['end'].picked[i]) == 0
  assert bool(outcome['end'].in_play[i, CUBE])


def test_grasp_across_a_narrow_gap_never_takes_both(outcome):
  i = outcome['index']['gap']
  assert int(outcome['info'].picked[i]) <= 1
  assert int(outcome['end'].in_play[i, FLAT]) + int(outcome['end'].in_play[i, FLAT2]) >= 1


def test_push_moves_cube_about_10cm_along_direction(env, outcome):
  start, end, idx = outcome['start'], outcome['end'], outcome['index']
  before = jax.vmap(env.object_positions)(start)[:, CUBE]
  after = jax.vmap(env.object_positions)(end)[:, CUBE]
  for k in PUSH_ROTATIONS:
    i = idx[f'push{k}']
    a = float(rotation_angle(k))
    move = np.asarray(after[i] - before[i])
    along = move[0] * np.cos(a) + move[1] * np.sin(a)
    across = -move[0] * np.sin(a) + move[1] * np.cos(a)
    assert 0.07 <= along <= 0.13, f'rotation {k}: moved {along:.3f} m along the push'
    assert abs(across) < 0.03, f'rotation {k}: drifted {across:.3f} m sideways'
    assert bool(end.in_play[i, CUBE]) and not bool(outcome['info'].grasp_success[i])
    assert int(outcome['info'].lost[i]) == 0


def test_fingers_on_the_seam_of_touching_cubes_lift_neither(env, outcome):
  """The force-limited descent stops the fingers on the cubes' tops: they neither wedge into the
  seam nor pry the cubes apart (scene.press_force); closing, they may drag both along it."""
  end, info = outcome['end'], outcome['info']
  for name, i in outcome['index'].items():
    if not name.startswith('seam'):
      continue
    assert int(info.picked[i]) == 0 and not bool(info.grasp_success[i]), name
    assert bool(end.in_play[i, CUBE]) and bool(end.in_play[i, CUBE2]), name
    cubes = np.asarray(env.object_positions(jax.tree.map(lambda x: x[i], end)))[[CUBE, CUBE2]]
    assert abs(cubes[1, 0] - cubes[0, 0] - 2 * SEAM) < 0.005, f'{name}: cubes at {cubes}'


def test_push_separates_a_block_from_a_row(env, outcome):
  start, end, i = outcome['start'], outcome['end'], outcome['index']['row']
  moved = np.asarray(jax.vmap(env.object_positions)(end)[i]
                     - jax.vmap(env.object_positions)(start)[i])
  assert moved[CUBE, 1] > 0.06, f'pushed cube moved {moved[CUBE, 1]:.3f} m'
  for other in (FLAT, CUBE2):
    assert np.linalg.norm(moved[other, :2]) < 0.02, f'slot {other} dragged {moved[other, :2]}'


def test_a_push_stops_at_the_workspace_edge(env):
  """The simulator's push follows the robot's contract (`sim.contract.push_length`): the fingers
  slide the trained length from well inside, and stop at the border from 3 cm before it."""
  half, length = env.config.scene.workspace_half, env.config.env.push_length
  for x0, end in ((0.0, length), (half - 0.03, half)):
    action = jax.tree.map(lambda v: v[0], actions([(PUSH, 0, x0, 0.0, 0.05)]))
    _, ctrl = env._begin(env.place(layout(env, [(CUBE, 0.1, 0.1, 0.0)])), action)
    np.testing.assert_allclose(float(np.asarray(ctrl)[-1, 0]), end, atol=1e-6)
    assert np.asarray(ctrl)[:, 0].max() <= max(end, x0) + 1e-6


def test_push_over_the_border_loses_the_cube(outcome):
  """Lost: out of play, counted, named in the step's mask, not picked."""
  info, end, i = outcome['info'], outcome['end'], outcome['index']['edge']
  assert int(info.lost[i]) == 1 and int(end.lost[i]) == 1
  assert np.asarray(info.left_workspace[i]).nonzero()[0].tolist() == [CUBE]
  assert not bool(end.in_play[i, CUBE]) and int(end.picked[i]) == 0


def test_unhealthy_env_is_detected_reset_and_counted(env, compiled, outcome):
  """Training's path: a step flags the environments whose physics broke (a NaN velocity, a NaN
  control), the reserve swaps in fresh ones, counted; the others carry on untouched."""
  _, step = compiled
  start = outcome['start']
  b = start.in_play.shape[0]
  bad = start.replace(sim=start.sim.replace(qvel=start.sim.qvel.at[0, 7].set(jnp.nan)))
  rows = [(GRASP, 0, 0.1, 0.1, 0.0)] * b
  rows[1] = (GRASP, 0, np.nan, 0.1, 0.0)
  after, info = step(bad, actions(rows))
  healthy = np.asarray(info.healthy)
  assert not healthy[:2].any() and healthy[2:].all()
  # The reserve: the outcome's own start states (settled drops) stand in for fresh ones.
  spare = reserve_lib.Reserve(states=jax.tree.map(lambda x: jnp.concatenate([x, x]), start),
                              available=jnp.int32(2 * b))
  healed, spare = jax.jit(reserve_lib.swap_in)(spare, after, ~info.healthy)
  assert np.asarray(healed.healthy).all() and int(spare.available) == 2 * b - 2
  assert np.asarray(healed.health_resets).tolist() == [1, 1] + [0] * (b - 2)
  assert np.isfinite(np.asarray(healed.sim.qpos[:2])).all()
  np.testing.assert_array_equal(np.asarray(healed.sim.qpos[:2]),  # the reserve's top two
                                np.asarray(start.sim.qpos)[[b - 1, b - 2]])
  np.testing.assert_array_equal(np.asarray(healed.sim.qpos[2:]), np.asarray(after.sim.qpos[2:]))


def test_step_and_settle_ends_as_step_and_settle_apart(env, compiled, outcome):
  """Training's one physics loop (a primitive, then fresh drops settling in the same loop) ends
  where `step` and `settle` run apart on the same batch end; without `settle` the drops come
  back untouched."""
  i = [outcome['index'][n] for n in ('grasp0', 'push0')]
  start = jax.tree.map(lambda x: x[np.asarray(i)], outcome['start'])
  act = actions([(GRASP, 0, *CUBE_AT, 0.05), (PUSH, 0, -0.05, 0.0, 0.05)])
  drops = jax.jit(jax.vmap(env.drop))(jax.random.split(jax.random.PRNGKey(4), 2))
  both = jax.jit(jax.vmap(env.step_and_settle, in_axes=(0, 0, 0, None)))
  stepped, info, settled = both(start, act, drops, True)
  alone, _ = compiled[1](start, act)
  apart = jax.jit(jax.vmap(env.settle))(drops)
  assert np.asarray(info.grasp_success).tolist() == [True, False]
  for got, want in ((stepped, alone), (settled, apart)):
    np.testing.assert_allclose(np.asarray(got.sim.qpos), np.asarray(want.sim.qpos), atol=1e-4)
    assert np.array_equal(np.asarray(got.in_play), np.asarray(want.in_play))
  assert not np.allclose(np.asarray(settled.sim.qpos), np.asarray(drops.sim.qpos), atol=1e-3)
  stepped, _, kept = both(start, act, drops, False)
  np.testing.assert_allclose(np.asarray(stepped.sim.qpos), np.asarray(alone.sim.qpos), atol=1e-4)
  for got, want in zip(jax.tree.leaves(kept), jax.tree.leaves(drops)):
    assert np.array_equal(np.asarray(got), np.asarray(want))
