"""Drops objects on B tabletops, runs a few grasps and pushes in lockstep, prints what happened.

A look at the physics alone, without perception or learning: actions are aimed at objects from
their true poses (grasps on the top of a random object in play, pushes from 5 cm beside it).

  mvcoba-demo [--config default|paper|tiny|FILE] [--set num_envs=4] [--actions 4]
"""
from __future__ import annotations

import argparse
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np
from tqdm import tqdm

from mvcoba_jax import config as config_lib
from mvcoba_jax import runtime
from mvcoba_jax.sim import physics, primitives
from mvcoba_jax.sim.geometry import rotation_angle
from mvcoba_jax.sim.primitives import Action
from mvcoba_jax.sim.tabletop import Tabletop


def aimed_actions(env: Tabletop, states, key, primitive: int) -> Action:
  """One action per environment at a random object in play (true poses, no perception)."""
  b = states.in_play.shape[0]
  k_obj, k_rot = jax.random.split(key)
  logits = jnp.where(states.in_play, 0.0, -jnp.inf)
  slot = jax.random.categorical(k_obj, logits)
  pos = jax.vmap(env.object_positions)(states)[jnp.arange(b), slot]
  rotation = jax.random.randint(k_rot, (b,), 0, env.config.env.num_rotations)
  angle = rotation_angle(rotation, env.config.env.num_rotations)
  back = jnp.where(primitive == primitives.PUSH, 0.05, 0.0)
  top = pos[:, 2] + 0.025  # most blocks are 5 cm tall in their resting pose
  return Action(primitive=jnp.full(b, primitive, jnp.int32), rotation=rotation,
                x=pos[:, 0] - back * jnp.cos(angle), y=pos[:, 1] - back * jnp.sin(angle), z=top)


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  config_lib.add_arguments(parser)
  parser.add_argument('--actions', type=int, default=4, help='primitives per environment')
  args = parser.parse_args(argv)
  if args.actions < 1:
    parser.error(f'--actions {args.actions}: at least 1')
  try:
    config = config_lib.from_arguments(args)
  except config_lib.ConfigError as e:
    parser.error(str(e))
  problem = physics.device_problem(config.scene)
  if problem:  # as training refuses it
    parser.error(problem)
  runtime.setup()
  env = Tabletop(config.tabletop)
  b = config.num_envs
  print(f'{b} tabletops, {config.env.num_objects} objects each, pool of {env.num_slots} slots. '
        f'Compiling reset and step on the {env.backend.name} backend (cached after the first '
        'time).')
  reset = jax.jit(jax.vmap(env.reset))
  step = jax.jit(jax.vmap(env.step))
  key = jax.random.PRNGKey(config.seed)
  key, k_reset = jax.random.split(key)
  t0 = time.perf_counter()
  states = jax.block_until_ready(reset(jax.random.split(k_reset, b)))
  print(f'reset: {time.perf_counter() - t0:.1f} s; objects in play per table: '
        f'{np.asarray(states.in_play.sum(axis=1)).tolist()}')

  attempts = successes = 0
  for i in tqdm(range(args.actions), desc='primitives', unit='batch'):
    primitive = primitives.GRASP if i % 2 == 0 else primitives.PUSH
    key, k_act = jax.random.split(key)
    states, info = step(states, aimed_actions(env, states, k_act, primitive))
    if primitive == primitives.GRASP:
      attempts += b
      successes += int(info.grasp_success.sum())
    name = 'grasp' if primitive == primitives.GRASP else 'push'
    tqdm.write(f'action {i + 1} ({name}): success {np.asarray(info.grasp_success).astype(int)}'
               f' picked {np.asarray(info.picked)} lost {np.asarray(info.lost)}'
               f' healthy {np.asarray(info.healthy).astype(int)}')
  print(f'grasp success {successes}/{attempts}; objects picked {int(states.picked.sum())}, lost '
        f'{int(states.lost.sum())}; total {time.perf_counter() - t0:.1f} s')
  return 0


if __name__ == '__main__':
  sys.exit(main())
