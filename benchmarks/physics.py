"""Physics throughput of the backends on the same scene, and of raw MuJoCo for reference.

Prints one JSON object: for each object count and batch size, env-steps/s and primitives/s of
`jit(vmap(env.step))` (a grasp at an object, the full scripted primitive) on the native backend,
the same on MJX's JAX implementation (at the `--mjx-batch` sizes only: its programs take minutes
to compile) and on MuJoCo Warp (at the `--warp-batch` sizes), and the same start states and
control sequences stepped by raw `mujoco.rollout` and `mujoco.batch.Batch.rollout` outside JAX
(what the native backend's JAX bridge costs), with the ratios measured in the same run.

  python benchmarks/physics.py [--batch 1 8 32] [--mjx-batch 8] [--warp-batch 8]
                               [--objects 10 30] [--repeats 3]
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import sys
import time

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402
from mujoco import batch as mjbatch  # noqa: E402
from mujoco import rollout  # noqa: E402

from mvcoba_jax import runtime  # noqa: E402
from mvcoba_jax.config import resolve  # noqa: E402
from mvcoba_jax.sim import primitives  # noqa: E402
from mvcoba_jax.sim.native import default_threads  # noqa: E402
from mvcoba_jax.sim.physics import resolve_backend  # noqa: E402
from mvcoba_jax.sim.primitives import Action  # noqa: E402
from mvcoba_jax.sim.tabletop import Tabletop  # noqa: E402

POOLS = {  # object slots per scene size; every slot is in play
    2: (('cube', 1), ('tall_box', 1)),  # device.sh --tiny: every step, compiled in the least time
    10: (('cube', 2), ('tall_box', 1), ('flat_box', 1), ('prism', 1), ('arch', 1),
         ('cylinder', 2), ('disk', 1), ('octagon', 1)),
    30: (('cube', 5), ('tall_box', 4), ('flat_box', 4), ('prism', 4), ('arch', 4),
         ('cylinder', 3), ('disk', 3), ('octagon', 3)),
}
CONTACT_LIMITS = {2: (8, 32), 10: (24, 96), 30: (48, 192)}  # MJX's max_geom_pairs, max_contact_points


def make_env(n: int, backend: str) -> Tabletop:
  base = resolve(None)
  pairs, points = CONTACT_LIMITS[n]
  scene = dataclasses.replace(base.scene, pool=POOLS[n], max_geom_pairs=pairs,
                              max_contact_points=points, backend=backend)
  return Tabletop(dataclasses.replace(base, scene=scene,
                                      env=dataclasses.replace(base.env, num_objects=n)).tabletop)


def timed(fn, *args, repeats: int):
  """(output, first call s, median of `repeats` later calls s, nan without any)."""
  t = time.perf_counter()
  out = jax.block_until_ready(fn(*args))
  first = time.perf_counter() - t
  runs = []
  for _ in range(repeats):
    t = time.perf_counter()
    jax.block_until_ready(fn(*args))
    runs.append(time.perf_counter() - t)
  return out, first, float(np.median(runs)) if runs else float('nan')


def grasp_actions(env: Tabletop, states) -> Action:
  """A grasp at the first object in play of every environment, from its top."""
  pos = jax.vmap(env.object_positions)(states)
  first = jnp.argmax(states.in_play, axis=1)
  target = pos[jnp.arange(pos.shape[0]), first]
  b = pos.shape[0]
  return Action(primitive=jnp.full(b, primitives.GRASP), rotation=jnp.zeros(b, jnp.int32),
                x=target[:, 0], y=target[:, 1], z=target[:, 2] + 0.02)


def backend_row(env: Tabletop, states, actions, repeats: int) -> dict:
  step = jax.jit(jax.vmap(env.step))
  (_, info), first, wall = timed(step, states, actions, repeats=repeats)
  b, steps = actions.x.shape[0], env.script.length
  return {'step_compile_s': first - wall, 'primitive_wall_s': wall,
          'env_steps_per_s': b * steps / wall, 'primitives_per_s': b / wall,
          'grasp_success': float(np.mean(np.asarray(info.grasp_success))),
          'healthy': float(np.mean(np.asarray(info.healthy)))}


def raw_rows(env: Tabletop, states, actions: Action, repeats: int) -> dict:
  """The same start states and controls stepped by MuJoCo directly, no JAX in between."""
  m, script, b = env.scene.mj_model, env.script, actions.x.shape[0]
  ts = jnp.arange(script.length)
  scene = env.config.scene
  ctrl = np.asarray(jax.vmap(lambda a: jax.vmap(
      lambda t: primitives.target(script, a, env.config.env, scene.gripper, scene.workspace_half,
                                  t))(ts))(actions), np.float64)
  start = np.asarray(jax.vmap(lambda a: primitives.start_pose(a, env.config.env, scene.gripper))(
      actions))
  qpos = np.asarray(states.sim.qpos, np.float64)
  qpos[:, env.scene.index.gripper_qpos] = start
  threads = default_threads()

  spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
  init = np.zeros((b, mujoco.mj_stateSize(m, spec)))
  d = mujoco.MjData(m)
  for i in range(b):
    d.qpos[:] = qpos[i]
    mujoco.mj_getState(m, d, init[i], spec)
  datas = [mujoco.MjData(m) for _ in range(threads)]

  def with_rollout():
    rollout.rollout(m, datas, init, ctrl)

  batch = mjbatch.Batch(m, b, nthread=min(threads, b))

  def with_batch():
    batch.state[:] = 0.0
    batch.qpos[:] = qpos
    batch.rollout(script.length, ctrl, record=())

  out = {}
  for name, fn in (('rollout', with_rollout), ('batch', with_batch)):
    fn()
    runs = []
    for _ in range(repeats):
      t = time.perf_counter()
      fn()
      runs.append(time.perf_counter() - t)
    out[f'raw_{name}_env_steps_per_s'] = b * script.length / float(np.median(runs))
  return out


def bench(n: int, batch: int, mjx: bool, warp: bool, repeats: int) -> dict:
  native_env = make_env(n, 'native')
  keys = jax.random.split(jax.random.PRNGKey(0), batch)
  states = jax.jit(jax.vmap(native_env.reset))(keys)
  actions = grasp_actions(native_env, states)
  row = {'objects': n, 'batch': batch, 'physics_steps_per_primitive': native_env.script.length,
         'native': backend_row(native_env, states, actions, repeats)}
  row.update(raw_rows(native_env, states, actions, repeats))
  nat = row['native']['env_steps_per_s']
  row['native_over_raw_rollout'] = nat / row['raw_rollout_env_steps_per_s']
  row['native_over_raw_batch'] = nat / row['raw_batch_env_steps_per_s']
  if mjx:  # the same settled states, stepped by MJX
    row['mjx'] = backend_row(make_env(n, 'mjx'), states, actions, repeats)
    row['native_over_mjx'] = nat / row['mjx']['env_steps_per_s']
  if warp:  # the same settled states, stepped by MuJoCo Warp
    row['warp'] = backend_row(make_env(n, 'warp'), states, actions, repeats)
    row['warp_over_native'] = row['warp']['env_steps_per_s'] / nat
  return row


def settings() -> dict:
  """The physics settings and software every physics benchmark reports."""
  base = resolve(None)
  return {
      'timestep': base.scene.timestep, 'solver': 'Newton', 'jacobian': 'sparse',
      'iterations': base.scene.iterations, 'ls_iterations': base.scene.ls_iterations,
      'cone': 'pyramidal', 'backend': resolve_backend(base.scene),
      'native_threads': default_threads(),
      'jax': jax.__version__, 'mujoco': mujoco.__version__, 'device': str(jax.devices()[0]),
      'cpu_count': os.cpu_count(), 'machine': platform.machine(),
  }


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--batch', type=int, nargs='+', default=[1, 8, 32])
  parser.add_argument('--mjx-batch', type=int, nargs='*', default=[8],
                      help='batch sizes at which MJX is measured too (none: native only)')
  parser.add_argument('--warp-batch', type=int, nargs='*', default=[],
                      help='batch sizes at which MuJoCo Warp is measured too')
  parser.add_argument('--objects', type=int, nargs='+', default=[10, 30], choices=sorted(POOLS))
  parser.add_argument('--repeats', type=int, default=3)
  parser.add_argument('--cache', action='store_true',
                      help='use the persistent compilation cache (compile times then mean little)')
  args = parser.parse_args()
  if args.cache:
    runtime.setup()
  rows = []
  for n in args.objects:
    for b in args.batch:
      rows.append(bench(n, b, b in args.mjx_batch, b in args.warp_batch, args.repeats))
      print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
  print(json.dumps({
      'benchmark': 'physics',
      'settings': {
          **settings(), 'contact_limits_mjx': CONTACT_LIMITS, 'pools': POOLS,
          'primitive': 'grasp at the first object in play, full script, from settled drops',
          'persistent_compilation_cache': args.cache,
      },
      'results': rows,
  }, indent=1))


if __name__ == '__main__':
  main()
