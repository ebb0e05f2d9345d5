"""The native MuJoCo backend's own promises: the choice of backend, results independent of the
thread count and of concurrent callers, and the parked slots it keeps out of the scene."""
import concurrent.futures

import jax
import numpy as np
import pytest

from mvcoba_jax.config import ConfigError, override, resolve
from mvcoba_jax.sim import physics
from mvcoba_jax.sim.primitives import GRASP, PUSH
from mvcoba_jax.sim.tabletop import Tabletop
from tests.helpers import actions, layout, make_env, stack

CUBE, CUBE2, FLAT = 0, 1, 2


def test_auto_is_native_on_a_cpu_and_a_bad_name_is_refused():
  config = resolve('tiny')
  assert config.scene.backend == 'auto'
  assert physics.resolve_backend(config.scene) == 'native'  # the tests run on a CPU
  with pytest.raises(ConfigError, match=r"scene.backend='jax': allowed values are auto, native"):
    physics.resolve_backend(override(config, 'scene.backend=jax').scene)


def run(threads: int):
  """Settles three layouts and runs a grasp, a push and a grasp at nothing on them."""
  env = make_env('tiny', 'native', f'scene.native_threads={threads}')
  layouts = stack([layout(env, [(CUBE, 0.03, -0.02, 0.3), (FLAT, -0.08, 0.06, 0.0)]),
                   layout(env, [(CUBE, 0.0, 0.0, 0.0), (CUBE2, 0.1, 0.1, 0.0)]),
                   layout(env, [(FLAT, 0.05, 0.05, 1.0)])])
  start = jax.jit(jax.vmap(env.reset_from_case))(layouts)
  end, info = jax.jit(jax.vmap(env.step))(start, actions([
      (GRASP, 3, 0.03, -0.02, 0.05), (PUSH, 0, -0.05, 0.0, 0.05), (GRASP, 0, -0.1, -0.1, 0.0)]))
  return env, start, end, info


def test_results_do_not_depend_on_the_thread_count():
  _, start1, end1, info1 = run(1)
  env, start2, end2, info2 = run(2)
  for a, b in [(start1.sim, start2.sim), (end1.sim, end2.sim), (info1, info2)]:
    jax.tree.map(np.testing.assert_array_equal, a, b)
  assert np.asarray(info2.grasp_success).tolist() == [True, False, False]
  # Parked slots stayed exactly at their parking spots through the settle and the primitive.
  park = np.asarray(physics.parked_slot_qpos(env.scene))
  qpos = np.asarray(end2.sim.qpos)[:, np.asarray(env._parking.qpos_idx)]
  parked = ~np.asarray(end2.in_play)
  np.testing.assert_array_equal(qpos[parked], np.broadcast_to(park, qpos.shape)[parked])


def test_concurrent_callers_get_the_results_of_callers_one_at_a_time():
  """The shards of several devices call the host side at once; each gets its own answer."""
  env = make_env('tiny', 'native')
  keys = jax.random.split(jax.random.PRNGKey(3), 4)
  states = jax.jit(jax.vmap(env.place))(jax.vmap(env.sample_layout)(keys))
  sim = jax.tree.map(np.asarray, states.sim)
  hold = np.broadcast_to(np.asarray(env._gripper_park), (4, 200, 6))
  parked = ~np.asarray(states.in_play)
  call = lambda i: env.backend._simulate_host((), sim.qpos[i:i + 1], sim.qvel[i:i + 1],
                                              sim.mocap_pos[i:i + 1], sim.mocap_quat[i:i + 1],
                                              parked[i:i + 1], hold[i:i + 1], np.int32(200))
  alone = [call(i) for i in range(4)]
  with concurrent.futures.ThreadPoolExecutor(4) as pool:
    together = list(pool.map(call, range(4)))
  for a, b in zip(alone, together):
    for x, y in zip(a, b):
      np.testing.assert_array_equal(x, y)
  assert not np.array_equal(alone[0][0], alone[1][0])


def test_frames_of_a_primitive_end_where_the_step_ends():
  """`Tabletop(frames=F)` records F snapshots inside the same physics call: they change during
  the primitive and the last one holds the objects where the step leaves them."""
  env = Tabletop(resolve('tiny').tabletop, frames=3)
  assert len(env.frames) == 3 and env.frames[-1] == env.script.length - 1
  state = jax.jit(env.reset_from_case)(layout(env, [(CUBE, 0.0, 0.0, 0.0)]))
  action = actions([(PUSH, 0, -0.05, 0.0, 0.05)])  # pushed 10 cm along +x
  end, info = jax.jit(jax.vmap(env.step))(jax.tree.map(lambda x: x[None], state), action)
  frames = np.asarray(info.frames[0])
  assert frames.shape == (3, env.scene.mj_model.nq)
  cube = np.asarray(env._qpos_idx[CUBE])
  assert frames[-1][cube[0]] - frames[0][cube[0]] > 0.03  # the cube moves along the frames
  np.testing.assert_array_equal(frames[-1][cube], np.asarray(end.sim.qpos[0])[cube])
