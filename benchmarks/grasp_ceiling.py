"""What the grasp physics allows: an oracle grasp at the centre of each isolated shape.

Each shape of the default pool rests alone on the table at a yaw that is not a multiple of
22.5 degrees, and is grasped at its centre, at its top surface, at every one of the 16 rotations,
all in one batch of `jax.vmap(env.step)`. Prints JSON: per shape, which rotations lifted it, the
fraction of rotations that did, and whether any did. A shape that no rotation lifts caps what
any policy can reach; one that few rotations lift is hard to learn. `--gripper` measures it for
each named gripper preset (`sim/grippers.py`) in turn; `--set` changes the default preset (another
`scene.pool`: other shapes, mesh objects).

  python benchmarks/grasp_ceiling.py [--yaw-deg 10] [--gripper rg2 robotiq_2f85 franka_hand]
                                     [--set scene.pool=package:sim/objects/everyday/mug:1,...]
"""
from __future__ import annotations

import argparse
import json
import platform
import time

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from mvcoba_jax import runtime  # noqa: E402
from mvcoba_jax.config import resolve  # noqa: E402
from mvcoba_jax.sim import shapes  # noqa: E402
from mvcoba_jax.sim.primitives import GRASP, Action  # noqa: E402
from mvcoba_jax.sim.scenarios import (  # noqa: E402
  Case,
  CaseObject,
  case_to_layout,
  rest_height,
  rest_quat,
  stack_layouts,  # noqa: E402
)
from mvcoba_jax.sim.tabletop import Tabletop  # noqa: E402

CENTRE = (0.02, -0.03)


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--yaw-deg', type=float, default=10.0, help='yaw of every shape')
  parser.add_argument('--gripper', nargs='+', default=['rg2'], help='gripper presets')
  parser.add_argument('--set', nargs='*', default=[], metavar='KEY=VALUE',
                      help='overrides of the default preset')
  args = parser.parse_args()
  runtime.setup()
  out = {g: ceiling(Tabletop(resolve(None, [f'scene.gripper={g}', *args.set]).tabletop),
                    args.yaw_deg) for g in args.gripper}
  print(json.dumps(out, indent=1))


def ceiling(env: Tabletop, yaw_deg: float) -> dict:
  """Per shape of the pool, the rotations whose grasp at its centre lifted it."""
  names = list(dict.fromkeys(env.scene.index.slot_shapes))  # each shape of the pool once
  rotations = env.config.env.num_rotations
  layouts, rows = [], []
  for name in names:
    alone = CaseObject(name, (0.5, 0.5, 0.5), (*CENTRE, rest_height(name)),
                       rest_quat(name, np.deg2rad(yaw_deg)), line=0)
    layouts += [case_to_layout(Case(name, 'grasp_ceiling', (alone,)), env)] * rotations
    top = float(shapes.shape(name).rest_extent[2])
    rows += [(k, *CENTRE, top) for k in range(rotations)]
  batch = stack_layouts(layouts)
  k, x, y, z = (np.array(c) for c in zip(*rows))
  actions = Action(primitive=jnp.full(len(rows), GRASP, jnp.int32),
                   rotation=jnp.asarray(k, jnp.int32), x=jnp.asarray(x, jnp.float32),
                   y=jnp.asarray(y, jnp.float32), z=jnp.asarray(z, jnp.float32))
  t0 = time.perf_counter()
  start = jax.jit(jax.vmap(env.reset_from_case))(batch)
  _, info = jax.jit(jax.vmap(env.step))(start, actions)
  success = np.asarray(info.grasp_success).reshape(len(names), rotations)
  seconds = time.perf_counter() - t0
  per_shape = {name: dict(lifted_at_rotations=np.flatnonzero(success[i]).tolist(),
                          fraction=float(success[i].mean()), any=bool(success[i].any()))
               for i, name in enumerate(names)}
  return dict(
      settings=dict(yaw_deg=yaw_deg, centre=CENTRE, rotations=rotations, batch=len(rows),
                    gripper=env.config.scene.gripper.name, backend=jax.default_backend(),
                    machine=platform.machine(), jax=jax.__version__),
      shapes=per_shape,
      mean_fraction=float(success.mean()),
      seconds_with_compile=round(seconds, 1))


if __name__ == '__main__':
  main()
