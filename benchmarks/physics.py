"""Physics throughput: batched MJX primitives vs native MuJoCo on the same scene.

Prints one JSON object: for each object count and batch size, the compile times of `reset` and
`step`, env-steps/s and primitives/s of `jax.vmap(env.step)` (a grasp at a random object, the
full scripted primitive), and the same scene and control sequence stepped by native MuJoCo
(`mj_step` in a loop, and `mujoco.rollout` on 2 threads) for comparison.

  python benchmarks/physics.py [--batch 1 8 32] [--objects 10 30] [--repeats 2]
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import pathlib
import platform
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402
from mujoco import rollout  # noqa: E402

from envs import primitives  # noqa: E402
from envs.primitives import Action  # noqa: E402
from envs.tabletop import Tabletop  # noqa: E402
from mvcoba_jax.config import resolve  # noqa: E402
from mvcoba_jax.runtime import enable_compilation_cache  # noqa: E402

POOLS = {  # object slots per scene size; every slot is in play
    10: (('cube', 2), ('tall_box', 1), ('flat_box', 1), ('prism', 1), ('arch', 1),
         ('cylinder', 2), ('disk', 1), ('octagon', 1)),
    30: (('cube', 5), ('tall_box', 4), ('flat_box', 4), ('prism', 4), ('arch', 4),
         ('cylinder', 3), ('disk', 3), ('octagon', 3)),
}
CONTACT_LIMITS = {10: (24, 96), 30: (48, 192)}  # max_geom_pairs, max_contact_points


def make_env(n: int) -> Tabletop:
  base = resolve(None)
  pairs, points = CONTACT_LIMITS[n]
  scene = dataclasses.replace(base.scene, pool=POOLS[n], max_geom_pairs=pairs,
                              max_contact_points=points)
  return Tabletop(dataclasses.replace(base, scene=scene,
                                      env=dataclasses.replace(base.env, num_objects=n)))


def timed(fn, *args):
  t = time.perf_counter()
  out = jax.block_until_ready(fn(*args))
  return out, time.perf_counter() - t


def grasp_actions(env: Tabletop, states) -> Action:
  """A grasp at the first object in play of every environment, from its top."""
  pos = jax.vmap(env.object_positions)(states)
  first = jnp.argmax(states.in_play, axis=1)
  target = pos[jnp.arange(pos.shape[0]), first]
  b = pos.shape[0]
  return Action(primitive=jnp.full(b, primitives.GRASP), rotation=jnp.zeros(b, jnp.int32),
                x=target[:, 0], y=target[:, 1], z=target[:, 2] + 0.02)


def native(env: Tabletop, states, actions: Action, batch: int) -> dict:
  """The same start states and gripper targets stepped by MuJoCo's C library."""
  m = env.scene.mj_model
  script = env.script
  ts = jnp.arange(script.length)
  ctrl = np.asarray(jax.vmap(lambda a: jax.vmap(
      lambda t: primitives.target(script, a, env.config.env, t))(ts))(actions), np.float64)
  start_pose = np.asarray(jax.vmap(lambda a: primitives.start_pose(a, env.config.env))(actions))
  qpos = np.asarray(states.data.qpos, np.float64)
  qpos[:, env.scene.index.gripper_qpos] = start_pose
  d = mujoco.MjData(m)
  d.qpos[:] = qpos[0]
  t = time.perf_counter()
  for step in range(script.length):
    d.ctrl[:] = ctrl[0, step]
    mujoco.mj_step(m, d)
  loop = script.length / (time.perf_counter() - t)

  spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
  init = np.zeros((batch, mujoco.mj_stateSize(m, spec)))
  for b in range(batch):
    d = mujoco.MjData(m)
    d.qpos[:] = qpos[b]
    mujoco.mj_getState(m, d, init[b], spec)
  datas = [mujoco.MjData(m) for _ in range(2)]
  t = time.perf_counter()
  rollout.rollout(m, datas, init, ctrl)
  threaded = batch * script.length / (time.perf_counter() - t)
  return {'mj_step_loop_env_steps_per_s': loop, 'rollout_2_threads_env_steps_per_s': threaded}


def settings() -> dict:
  """The physics settings and software every physics benchmark reports."""
  base = resolve(None)
  return {
      'timestep': base.scene.timestep, 'solver': 'Newton', 'jacobian': 'sparse',
      'iterations': base.scene.iterations, 'ls_iterations': base.scene.ls_iterations,
      'cone': 'pyramidal',
      'native_note': 'native runs start from the same states and controls; parked objects '
                     'are not pinned there (they fall far outside the workspace)',
      'jax': jax.__version__, 'mujoco': mujoco.__version__, 'device': str(jax.devices()[0]),
      'cpu_count': os.cpu_count(), 'machine': platform.machine(),
  }


def bench(n: int, batch: int, repeats: int) -> dict:
  env = make_env(n)
  keys = jax.random.split(jax.random.PRNGKey(0), batch)
  reset = jax.jit(jax.vmap(env.reset))
  step = jax.jit(jax.vmap(env.step))
  states, reset_first = timed(reset, keys)
  _, reset_again = timed(reset, keys)
  actions = grasp_actions(env, states)
  (_, info), step_first = timed(step, states, actions)
  runs = [timed(step, states, actions)[1] for _ in range(repeats)]
  step_time = float(np.median(runs))
  steps = env.script.length
  row = {
      'objects': n, 'batch': batch, 'physics_steps_per_primitive': steps,
      'reset_compile_s': reset_first - reset_again, 'step_compile_s': step_first - step_time,
      'primitive_wall_s': step_time,
      'env_steps_per_s': batch * steps / step_time,
      'primitives_per_s': batch / step_time,
      'grasp_success': float(np.mean(np.asarray(info.grasp_success))),
      'healthy': float(np.mean(np.asarray(info.healthy))),
  }
  row.update(native(env, states, actions, batch))
  row['native_loop_over_mjx'] = row['mj_step_loop_env_steps_per_s'] / row['env_steps_per_s']
  return row


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--batch', type=int, nargs='+', default=[1, 8, 32])
  parser.add_argument('--objects', type=int, nargs='+', default=[10, 30], choices=sorted(POOLS))
  parser.add_argument('--repeats', type=int, default=2)
  parser.add_argument('--cache', action='store_true',
                      help='use the persistent compilation cache (compile times then mean little)')
  args = parser.parse_args()
  if args.cache:
    enable_compilation_cache()
  rows = []
  for n in args.objects:
    for b in args.batch:
      rows.append(bench(n, b, args.repeats))
      print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
  for n in args.objects:
    one = [r for r in rows if r['objects'] == n and r['batch'] == min(args.batch)][0]
    for r in rows:
      if r['objects'] == n:
        r['speedup_vs_smallest_batch'] = r['env_steps_per_s'] / one['env_steps_per_s']
  print(json.dumps({
      'benchmark': 'physics',
      'settings': {
          **settings(), 'contact_limits': CONTACT_LIMITS, 'pools': POOLS,
          'primitive': 'grasp at the first object in play, full script',
          'persistent_compilation_cache': args.cache,
      },
      'results': rows,
  }, indent=1))


if __name__ == '__main__':
  main()
