"""The shipped procedural training objects on native physics: each one, alone on the table, rests
where it was set down and is lifted by the scripted grasp at the centre of its first part at
some rotation; heap drops of the `objects` preset settle with what stays in play on the table."""
import jax
import numpy as np
import pytest

from mvcoba_jax.sim import meshes, procedural, shapes
from mvcoba_jax.sim.primitives import GRASP
from tests.helpers import actions, layout, make_env, stack

ROTATIONS = range(0, 16, 2)


@pytest.fixture(scope='module')
def env():
  return make_env('objects', 'native')


def test_every_training_object_is_lifted_at_some_rotation(env):
  slots = [env.scene.index.slot_shapes.index(meshes.absolute(str(p)))
           for p in procedural.training_objects()]
  layouts, rows = [], []
  for slot in slots:
    shape = shapes.shape(env.scene.index.slot_shapes[slot])
    first = np.asarray(shape.parts[0].vertices)
    centre = 0.5 * (first.min(0) + first.max(0))
    for k in ROTATIONS:
      layouts.append(layout(env, [(slot, 0.0, 0.0, 0.0)]))
      rows.append((GRASP, k, centre[0], centre[1], shape.extent[2]))
  start = jax.jit(jax.vmap(env.reset_from_case))(stack(layouts))
  _, info = jax.jit(jax.vmap(env.step))(start, actions(rows))
  lifted = np.asarray(info.grasp_success).reshape(len(slots), len(ROTATIONS))
  assert np.asarray(info.healthy).all()
  assert lifted.any(axis=1).all(), dict(zip(
      [p.name for p in procedural.training_objects()], lifted.sum(axis=1)))


def test_heap_drops_of_the_objects_preset_settle_on_the_table():
  env = make_env('objects', 'native', 'env.drop=heap')
  state = jax.jit(jax.vmap(env.reset))(jax.random.split(jax.random.PRNGKey(0), 16))
  pos = np.asarray(state.sim.qpos)[:, env.scene.index.slot_qpos[:, None] + np.arange(3)]
  in_play = np.asarray(state.in_play)
  # Heap drops lose an object over the border now and then, blocks as well (at seed 0 and 64
  # drops: 13 of the default's, 8 of this preset's); losing it is counted, not hidden.
  assert in_play.sum(axis=1).mean() >= 9.5
  inside = np.all(np.abs(pos[..., :2]) <= env.config.scene.workspace_half, axis=-1)
  assert (inside | ~in_play).all() and (pos[..., 2][in_play] < 0.2).all()
