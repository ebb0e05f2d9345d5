"""How far the native backend and another (MJX's JAX implementation or MuJoCo Warp) agree on the
same primitives and pictures from the same states.

Settles `--batch` random drops of the default preset once (native), then runs the same actions
on both backends from those states: a grasp at a random object in play, or a push 5 cm behind
one along a random direction (half of each). Prints one JSON object: the share of grasps whose
success agrees, each backend's grasp success, how far each object in play ended apart (median,
p90, max), the health flags, and the share of heightmap cells of the settled states that agree
within 2 mm.

  python benchmarks/backend_agreement.py [--other mjx|warp] [--batch 32] [--seed 0]
"""
from __future__ import annotations

import argparse
import dataclasses
import json

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from physics import settings  # noqa: E402

from mvcoba_jax.config import resolve  # noqa: E402
from mvcoba_jax.learner import task  # noqa: E402
from mvcoba_jax.sim import primitives  # noqa: E402
from mvcoba_jax.sim.geometry import rotation_angle  # noqa: E402
from mvcoba_jax.sim.primitives import Action  # noqa: E402
from mvcoba_jax.sim.tabletop import Tabletop  # noqa: E402


def on(config, backend: str) -> task.Task:
  return task.Task.build(dataclasses.replace(
      config, scene=dataclasses.replace(config.scene, backend=backend)), (0, 1))


def random_actions(env: Tabletop, states, key) -> Action:
  """Grasps at (first half) and pushes towards (second half) a random object in play."""
  b = states.in_play.shape[0]
  k_obj, k_rot = jax.random.split(key)
  pick = jax.random.categorical(k_obj, jnp.where(states.in_play, 0.0, -jnp.inf))
  pos = jax.vmap(env.object_positions)(states)[jnp.arange(b), pick]
  rotation = jax.random.randint(k_rot, (b,), 0, env.config.env.num_rotations)
  angle = rotation_angle(rotation, env.config.env.num_rotations)
  grasp = jnp.arange(b) < b // 2
  back = jnp.where(grasp, 0.0, 0.05)
  return Action(primitive=jnp.where(grasp, primitives.GRASP, primitives.PUSH).astype(jnp.int32),
                rotation=rotation.astype(jnp.int32), x=pos[:, 0] - back * jnp.cos(angle),
                y=pos[:, 1] - back * jnp.sin(angle), z=pos[:, 2] + 0.02)


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--batch', type=int, default=32)
  parser.add_argument('--seed', type=int, default=0)
  parser.add_argument('--other', choices=('mjx', 'warp'), default='mjx')
  args = parser.parse_args()
  config = resolve(None)
  tasks = {'native': on(config, 'native'), args.other: on(config, args.other)}
  native, other = tasks['native'].env, tasks[args.other].env
  k_reset, k_act = jax.random.split(jax.random.PRNGKey(args.seed))
  states = jax.jit(jax.vmap(native.reset))(jax.random.split(k_reset, args.batch))
  actions = random_actions(native, states, k_act)
  out = {}
  maps = {}
  for name, one in tasks.items():
    maps[name] = jax.jit(one.observe)(states)
  for name, env in (('native', native), (args.other, other)):
    end, info = jax.jit(jax.vmap(env.step))(states, actions)
    out[name] = (jax.device_get(end), jax.device_get(info),
                 np.asarray(jax.vmap(env.object_positions)(end)))
  (_, info_n, pos_n), (_, info_m, pos_m) = out['native'], out[args.other]
  cells = ((np.asarray(maps['native'].seen) == np.asarray(maps[args.other].seen))
           & (np.abs(np.asarray(maps['native'].depth) - np.asarray(maps[args.other].depth))
              <= 0.002))
  grasp = np.asarray(actions.primitive) == primitives.GRASP
  in_play = np.asarray(states.in_play)
  both_kept = in_play & np.asarray(out['native'][0].in_play) & np.asarray(out[args.other][0].in_play)
  gap = np.linalg.norm(pos_n - pos_m, axis=-1)[both_kept]
  success_n, success_m = np.asarray(info_n.grasp_success), np.asarray(info_m.grasp_success)
  print(json.dumps({
      'benchmark': 'backend_agreement',
      'settings': {**settings(), 'batch': args.batch, 'seed': args.seed, 'other': args.other,
                   'actions': 'half grasps at a random object in play, half pushes 5 cm behind '
                              'one along a random rotation; start states settled natively'},
      'results': {
          'grasps': int(grasp.sum()),
          'grasp_success_native': float(success_n[grasp].mean()),
          f'grasp_success_{args.other}': float(success_m[grasp].mean()),
          'grasp_outcomes_agree': float((success_n == success_m)[grasp].mean()),
          'objects_compared': int(gap.size),
          'object_gap_m': {'median': float(np.median(gap)), 'p90': float(np.quantile(gap, 0.9)),
                           'max': float(gap.max())},
          'objects_lost_native': int(np.asarray(info_n.lost).sum()),
          f'objects_lost_{args.other}': int(np.asarray(info_m.lost).sum()),
          'healthy_native': float(np.asarray(info_n.healthy).mean()),
          f'healthy_{args.other}': float(np.asarray(info_m.healthy).mean()),
          'heightmap_cells_within_2mm': float(cells.mean()),
          'heightmap_cells_within_2mm_worst_view': float(cells.mean(axis=(2, 3)).min()),
      },
  }, indent=1))


if __name__ == '__main__':
  main()
