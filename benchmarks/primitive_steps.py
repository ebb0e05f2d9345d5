"""Physics steps per primitive, and whether a shorter script changes what the primitives do.

Settles `--batch` random drops of the default preset once (native), then runs the same actions
(backend_agreement's: half grasps at a random object in play, half pushes 5 cm behind one along a
random rotation) under the default preset's script and under the script with `--set` overrides
(e.g. `env.lift_height=0.15`). Prints one JSON object: each script's physics steps per grasp, per
push and per primitive (both run the longer one's count, in lockstep), the share of grasps whose
success agrees, how far each object in play after both came to rest apart after the pushes
(`--rest-steps` with the gripper parked; median, p90, max, the share within 2 cm), objects lost,
and the wall time of one batched step each (after compiling).

  python benchmarks/primitive_steps.py [--batch 128] [--seed 0] [--set KEY=VALUE ...]
"""
from __future__ import annotations

import argparse
import json
import time

import jax
import numpy as np
from backend_agreement import random_actions
from physics import settings

from mvcoba_jax.config import resolve
from mvcoba_jax.sim import primitives
from mvcoba_jax.sim.tabletop import Tabletop


def steps(env: Tabletop) -> dict:
  script = env.script
  return {'grasp': script.grasp_length, 'push': script.push_length, 'primitive': script.length}


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--batch', type=int, default=128)
  parser.add_argument('--seed', type=int, default=0)
  parser.add_argument('--rest-steps', type=int, default=250,
                      help='physics steps with the gripper parked after each primitive before '
                           'objects are compared, so that both compare where objects come to rest')
  parser.add_argument('--set', dest='overrides', action='append', default=[],
                      metavar='KEY=VALUE', help='a field of the shorter script, e.g. '
                      'env.lift_height=0.15')
  args = parser.parse_args()
  base = resolve(None, ['scene.backend=native'])
  short = resolve(None, ['scene.backend=native', *args.overrides])
  envs = {'default': Tabletop(base.tabletop), 'short': Tabletop(short.tabletop)}
  k_reset, k_act = jax.random.split(jax.random.PRNGKey(args.seed))
  states = jax.jit(jax.vmap(envs['default'].reset))(jax.random.split(k_reset, args.batch))
  actions = random_actions(envs['default'], states, k_act)
  out, wall = {}, {}
  for name, env in envs.items():
    step = jax.jit(jax.vmap(env.step))
    jax.block_until_ready(step(states, actions))
    start = time.perf_counter()
    end, info = jax.block_until_ready(step(states, actions))
    wall[name] = time.perf_counter() - start
    rest = jax.jit(jax.vmap(lambda s: env.settle(s, args.rest_steps)))(end)
    out[name] = (jax.device_get(end), jax.device_get(info),
                 np.asarray(jax.vmap(env.object_positions)(rest)))
  (end_d, info_d, pos_d), (end_s, info_s, pos_s) = out['default'], out['short']
  grasp = np.asarray(actions.primitive) == primitives.GRASP
  kept = np.asarray(states.in_play) & np.asarray(end_d.in_play) & np.asarray(end_s.in_play)
  gap = np.linalg.norm(pos_d - pos_s, axis=-1)[kept & ~grasp[:, None]]
  success_d, success_s = np.asarray(info_d.grasp_success), np.asarray(info_s.grasp_success)
  print(json.dumps({
      'benchmark': 'primitive_steps',
      'settings': {**settings(), 'batch': args.batch, 'seed': args.seed,
                   'short': args.overrides, 'backend': 'native', 'rest_steps': args.rest_steps,
                   'actions': 'half grasps at a random object in play, half pushes 5 cm behind '
                              'one along a random rotation; start states settled once'},
      'results': {
          'steps_default': steps(envs['default']), 'steps_short': steps(envs['short']),
          'grasps': int(grasp.sum()),
          'grasp_success_default': float(success_d[grasp].mean()),
          'grasp_success_short': float(success_s[grasp].mean()),
          'grasp_outcomes_agree': float((success_d == success_s)[grasp].mean()),
          'objects_compared_after_pushes': int(gap.size),
          'push_object_gap_m': {'median': float(np.median(gap)),
                                'p90': float(np.quantile(gap, 0.9)), 'max': float(gap.max())},
          'push_objects_within_2cm': float((gap <= 0.02).mean()),
          'objects_lost_default': int(np.asarray(info_d.lost).sum()),
          'objects_lost_short': int(np.asarray(info_s.lost).sum()),
          'step_wall_s_default': wall['default'], 'step_wall_s_short': wall['short'],
          'speedup': wall['default'] / wall['short'],
      },
  }, indent=1))


if __name__ == '__main__':
  main()
