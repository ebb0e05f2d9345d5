"""Training-step throughput and where its time goes: physics, rendering, the learner's parts.

Prints one JSON object: for each batch size B, bootstrap target (`train.target`: `--targets`) and
physics backend (native at every B, MJX at the `--mjx-batch` sizes, MuJoCo Warp at the
`--warp-batch` sizes), the compile time and the
steady-state wall time of the jitted training iteration (actions/s, updates/s), and the time of
its parts measured alone on the same states: the batched primitive (physics), render + heightmaps
(rendering), the 16-rotation acting forward, the target network's forward on a sampled batch of
next states (`network` target only; part of the update) and the whole SGD update. `--versus`
measures a second configuration, the first with more overrides, in the same run, and gives each
of its figures over the first's.

  python benchmarks/train.py [--config default] [--set KEY=VALUE] [--batch 1 8 32]
      [--targets network acting] [--mjx-batch 8] [--warp-batch 64] [--versus KEY=VALUE ...]
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
from physics import timed  # noqa: E402

from mvcoba_jax import config as config_lib  # noqa: E402
from mvcoba_jax.learner import agent  # noqa: E402
from mvcoba_jax.learner.training import Trainer  # noqa: E402


def bench(config, batch: int, target: str, backend: str, repeats: int) -> dict:
  config = dataclasses.replace(config, num_envs=batch,
                               scene=dataclasses.replace(config.scene, backend=backend),
                               train=dataclasses.replace(config.train, target=target))
  trainer = Trainer(config)
  state, init_first, _ = timed(jax.jit(trainer.init), jax.random.PRNGKey(0), repeats=0)
  args = (jnp.bool_(True), jnp.float32(-1.0))
  (state, _), it_first, it_wall = timed(trainer.compiled(), state, *args, repeats=repeats)
  k = config.train.steps_per_iteration

  q = jax.jit(trainer.q_maps)
  tabletops = state.task
  _, _, forward = timed(q, state.params, tabletops.obs, repeats=repeats)
  action = agent.greedy_actions(q(state.params, tabletops.obs), tabletops.changed,
                                trainer.method)
  world = trainer.task.to_world(action, tabletops.obs.depth)
  _, _, physics = timed(jax.jit(jax.vmap(trainer.task.env.step)), tabletops.env, world,
                        repeats=repeats)
  _, _, rendering = timed(jax.jit(trainer.observe), tabletops.env, repeats=repeats)
  _, _, update = timed(jax.jit(trainer.update), state, jax.random.PRNGKey(2), repeats=repeats)
  parts = {'physics': physics, 'rendering': rendering, 'network_act_forward': forward,
           'network_update': update}
  if target == 'network':  # the update's target forward, alone: batch_size sampled next states
    sampled = jax.tree.map(lambda x: jnp.resize(x, (config.train.batch_size,) + x.shape[1:]),
                           tabletops.obs)
    _, _, parts['network_target_in_update'] = timed(q, state.target_params, sampled,
                                                    repeats=repeats)
  return {
      'batch': batch, 'target': target, 'backend': backend, 'init_first_call_s': init_first,
      'iteration_compile_s': it_first - it_wall, 'iteration_wall_s': it_wall,
      'actions_per_s': batch * k / it_wall,
      'updates_per_s': k * config.updates_per_step / it_wall,
      'per_action_step_s': parts,
  }


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  config_lib.add_arguments(parser)
  parser.add_argument('--batch', type=int, nargs='+', default=[1, 8, 32])
  parser.add_argument('--mjx-batch', type=int, nargs='*', default=[8],
                      help='batch sizes at which the MJX backend is measured too')
  parser.add_argument('--warp-batch', type=int, nargs='*', default=[],
                      help='batch sizes at which the Warp backend is measured too')
  parser.add_argument('--targets', nargs='+', default=['network', 'acting'],
                      choices=config_lib.TARGETS, help='train.target values to measure')
  parser.add_argument('--repeats', type=int, default=2)
  parser.add_argument('--versus', nargs='+', default=[], metavar='KEY=VALUE',
                      help='overrides of a second configuration measured in the same run')
  args = parser.parse_args()
  config = config_lib.from_arguments(args)
  variants = [('base', config)]
  if args.versus:
    versus = config
    try:
      for assignment in args.versus:
        versus = config_lib.override(versus, assignment)
      variants.append(('versus', config_lib.validate(versus)))
    except config_lib.ConfigError as e:
      parser.error(f'--versus: {e}')
  rows = []
  for b in args.batch:
    for target in args.targets:
      backends = ['native'] + ['mjx'] * (b in args.mjx_batch) + ['warp'] * (b in args.warp_batch)
      for backend in backends:
        for name, variant in variants:
          rows.append({'variant': name, **bench(variant, b, target, backend, args.repeats)})
          print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
  for r in rows:
    parts = dict(r['per_action_step_s'])
    parts.pop('network_target_in_update', None)  # inside network_update
    total = sum(parts.values())
    r['share_of_parts'] = {k: v / total for k, v in parts.items()}
    twin = lambda **kv: [o for o in rows if o['batch'] == r['batch'] and all(
        o[k] == v for k, v in {'variant': r['variant'], **kv}.items())]
    for other in ('mjx', 'warp'):
      same = twin(backend=other, target=r['target'])
      if r['backend'] == 'native' and same:
        r[f'actions_per_s_over_{other}'] = r['actions_per_s'] / same[0]['actions_per_s']
    network = twin(backend=r['backend'], target='network')
    if r['target'] != 'network' and network:
      r['actions_per_s_over_network_target'] = r['actions_per_s'] / network[0]['actions_per_s']
    base = twin(variant='base', backend=r['backend'], target=r['target'])
    if r['variant'] == 'versus' and base:
      r['over_base'] = {'actions_per_s': r['actions_per_s'] / base[0]['actions_per_s'],
                        **{k: v / base[0]['per_action_step_s'][k]
                           for k, v in r['per_action_step_s'].items()}}
  print(json.dumps({'benchmark': 'train', 'config': args.config or 'default',
                    'overrides': args.overrides, 'versus': args.versus,
                    'settings': {'method': config.network.method,
                                 'steps_per_iteration': config.train.steps_per_iteration,
                                 'batch_size': config.train.batch_size,
                                 'replay_ratio': config.train.replay_ratio,
                                 'grid': round(2 * config.scene.workspace_half
                                               / config.perception.heightmap_resolution),
                                 'jax': jax.__version__, 'device': str(jax.devices()[0]),
                                 'cpu_count': os.cpu_count()},
                    'results': rows}, indent=1))


if __name__ == '__main__':
  main()
