"""What the grasp physics allows: an oracle grasp at the centre of each isolated shape.

Each shape of the default pool rests alone on the table at a yaw that is not a multiple of
22.5 degrees, and is grasped at its centre, at its top surface, at every one of the 16 rotations,
all in one batch of `jax.vmap(env.step)`. Prints JSON: per shape, which rotations lifted it, the
fraction of rotations that did, and whether any did. A shape that no rotation lifts caps what
any policy can reach; one that few rotations lift is hard to learn.

  python benchmarks/grasp_ceiling.py [--yaw-deg 10]
"""
from __future__ import annotations

import argparse
import json
import pathlib
import platform
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from envs import shapes  # noqa: E402
from envs.primitives import GRASP, Action  # noqa: E402
from envs.scene import park_position  # noqa: E402
from envs.tabletop import Layout, Tabletop  # noqa: E402
from mvcoba_jax.config import resolve  # noqa: E402
from mvcoba_jax.geometry import quat_mul, yaw_quat  # noqa: E402
from mvcoba_jax.runtime import enable_compilation_cache  # noqa: E402

CENTRE = (0.02, -0.03)


def isolated(env: Tabletop, slot: int, yaw: float) -> Layout:
  """Layout with only `slot` in play, resting at CENTRE with the given yaw."""
  m = env.num_slots
  shape = shapes.SHAPES[env.scene.index.slot_shapes[slot]]
  pos = np.array([park_position(i) for i in range(m)], np.float32)
  quat = np.tile(np.array([1, 0, 0, 0], np.float32), (m, 1))
  pos[slot] = (*CENTRE, 0.5 * shape.rest_extent[2] + 0.001)
  quat[slot] = np.asarray(quat_mul(yaw_quat(jnp.float32(yaw)), jnp.asarray(shape.rest_quat,
                                                                            jnp.float32)))
  occ_pos, occ_quat = env.parked_occluders()
  return Layout(in_play=jnp.asarray(np.arange(m) == slot), pos=jnp.asarray(pos),
                quat=jnp.asarray(quat), color=jnp.full((m, 3), 0.5),
                occluder_pos=occ_pos, occluder_quat=occ_quat)


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--yaw-deg', type=float, default=10.0, help='yaw of every shape')
  args = parser.parse_args()
  enable_compilation_cache()
  env = Tabletop(resolve(None))
  names = env.scene.index.slot_shapes
  slots = {name: names.index(name) for name in dict.fromkeys(names)}
  rotations = env.config.env.num_rotations
  layouts, rows = [], []
  for name, slot in slots.items():
    top = float(shapes.SHAPES[name].rest_extent[2])
    for k in range(rotations):
      layouts.append(isolated(env, slot, np.deg2rad(args.yaw_deg)))
      rows.append((k, *CENTRE, top))
  batch = jax.tree.map(lambda *x: jnp.stack(x), *layouts)
  k, x, y, z = (np.array(c) for c in zip(*rows))
  actions = Action(primitive=jnp.full(len(rows), GRASP, jnp.int32),
                   rotation=jnp.asarray(k, jnp.int32), x=jnp.asarray(x, jnp.float32),
                   y=jnp.asarray(y, jnp.float32), z=jnp.asarray(z, jnp.float32))
  t0 = time.perf_counter()
  start = jax.jit(jax.vmap(env.reset_from_case))(batch)
  _, info = jax.jit(jax.vmap(env.step))(start, actions)
  success = np.asarray(info.grasp_success).reshape(len(slots), rotations)
  seconds = time.perf_counter() - t0
  per_shape = {name: dict(lifted_at_rotations=np.flatnonzero(success[i]).tolist(),
                          fraction=float(success[i].mean()), any=bool(success[i].any()))
               for i, name in enumerate(slots)}
  print(json.dumps(dict(
      settings=dict(yaw_deg=args.yaw_deg, centre=CENTRE, rotations=rotations,
                    batch=len(rows), backend=jax.default_backend(), machine=platform.machine(),
                    jax=jax.__version__),
      shapes=per_shape,
      mean_fraction=float(success.mean()),
      seconds_with_compile=round(seconds, 1)), indent=1))


if __name__ == '__main__':
  main()
