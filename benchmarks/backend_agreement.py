"""How far the native and the MJX backends agree on the same primitives from the same states.

Settles `--batch` random drops of the default preset once (native), then runs the same actions
on both backends from those states: a grasp at a random object in play, or a push 5 cm behind
one along a random direction (half of each). Prints one JSON object: the share of grasps whose
success agrees, each backend's grasp success, how far each object in play ended apart (median,
p90, max), and the health flags.

  python benchmarks/backend_agreement.py [--batch 32] [--seed 0]
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
from mvcoba_jax.sim import primitives  # noqa: E402
from mvcoba_jax.sim.geometry import rotation_angle  # noqa: E402
from mvcoba_jax.sim.primitives import Action  # noqa: E402
from mvcoba_jax.sim.tabletop import Tabletop  # noqa: E402


def on(config, backend: str) -> Tabletop:
  return Tabletop(dataclasses.replace(config,
                                      scene=dataclasses.replace(config.scene, backend=backend)))


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
  args = parser.parse_args()
  config = resolve(None)
  native, mjx = on(config, 'native'), on(config, 'mjx')
  k_reset, k_act = jax.random.split(jax.random.PRNGKey(args.seed))
  states = jax.jit(jax.vmap(native.reset))(jax.random.split(k_reset, args.batch))
  actions = random_actions(native, states, k_act)
  out = {}
  for name, env in (('native', native), ('mjx', mjx)):
    end, info = jax.jit(jax.vmap(env.step))(states, actions)
    out[name] = (jax.device_get(end), jax.device_get(info),
                 np.asarray(jax.vmap(env.object_positions)(end)))
  (_, info_n, pos_n), (_, info_m, pos_m) = out['native'], out['mjx']
  grasp = np.asarray(actions.primitive) == primitives.GRASP
  in_play = np.asarray(states.in_play)
  both_kept = in_play & np.asarray(out['native'][0].in_play) & np.asarray(out['mjx'][0].in_play)
  gap = np.linalg.norm(pos_n - pos_m, axis=-1)[both_kept]
  success_n, success_m = np.asarray(info_n.grasp_success), np.asarray(info_m.grasp_success)
  print(json.dumps({
      'benchmark': 'backend_agreement',
      'settings': {**settings(), 'batch': args.batch, 'seed': args.seed,
                   'actions': 'half grasps at a random object in play, half pushes 5 cm behind '
                              'one along a random rotation; start states settled natively'},
      'results': {
          'grasps': int(grasp.sum()),
          'grasp_success_native': float(success_n[grasp].mean()),
          'grasp_success_mjx': float(success_m[grasp].mean()),
          'grasp_outcomes_agree': float((success_n == success_m)[grasp].mean()),
          'objects_compared': int(gap.size),
          'object_gap_m': {'median': float(np.median(gap)), 'p90': float(np.quantile(gap, 0.9)),
                           'max': float(gap.max())},
          'objects_lost_native': int(np.asarray(info_n.lost).sum()),
          'objects_lost_mjx': int(np.asarray(info_m.lost).sum()),
          'healthy_native': float(np.asarray(info_n.healthy).mean()),
          'healthy_mjx': float(np.asarray(info_m.healthy).mean()),
      },
  }, indent=1))


if __name__ == '__main__':
  main()
