"""Does the ordered suite force a push? An oracle grasp at the centre of every object, no push.

For each ordered case (in a scene holding just that case's objects), the case is reset once and
every object is grasped at its centre and top surface at each of 8 rotations (the half turn:
the fingers are symmetric), all in one batch of `jax.vmap(env.step)`. An object counts as
liftable when some rotation picks it (it leaves the table held by the fingers). In a case that
forces a push, the packed objects are not liftable. The control: every case of the isolated
suite (each shape alone, twice) grasped the same way at all 16 rotations; each shape should stay
liftable at nearly all of them.

  python benchmarks/ordered_graspability.py [--set scene.contact_timeconst=0.02] [--cases 00 02]
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import time

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from mvcoba_jax import config as config_lib  # noqa: E402
from mvcoba_jax import runtime  # noqa: E402
from mvcoba_jax.sim import shapes  # noqa: E402
from mvcoba_jax.sim.primitives import GRASP, Action  # noqa: E402
from mvcoba_jax.sim.scenarios import case_slots, case_to_layout, read_case  # noqa: E402
from mvcoba_jax.sim.tabletop import Tabletop  # noqa: E402
from mvcoba_jax.suites import suite_files  # noqa: E402
from mvcoba_jax.suites import cases as suite_cases  # noqa: E402

PACKED = 0.06  # an object with a neighbour centre this close is packed; others are isolated


def lift_table(path, base, rotations: int):
  """(case, (objects, rotations) bool: grasp at rotation k lifted the object) for one case file."""
  case = read_case(path)
  env = Tabletop(suite_cases.suite_config(base, suite_cases.pool_for([case])).tabletop)
  n = len(case.objects)
  start = jax.jit(env.reset_from_case)(case_to_layout(case, env))
  batch = jax.tree.map(lambda a: jnp.broadcast_to(a, (n * rotations, *a.shape)), start)
  xy = np.array([o.pos[:2] for o in case.objects])
  top = np.array([float(shapes.shape(o.shape).rest_extent[2]) for o in case.objects])
  obj = np.repeat(np.arange(n), rotations)
  actions = Action(primitive=jnp.full(n * rotations, GRASP, jnp.int32),
                   rotation=jnp.asarray(np.tile(np.arange(rotations), n), jnp.int32),
                   x=jnp.asarray(xy[obj, 0], jnp.float32), y=jnp.asarray(xy[obj, 1], jnp.float32),
                   z=jnp.asarray(top[obj], jnp.float32))
  after, info = jax.jit(jax.vmap(env.step))(batch, actions)
  slots = np.array(case_slots(case, env))[obj]
  gone = ~np.asarray(after.in_play)[np.arange(n * rotations), slots]
  # The target itself was picked (not a neighbour, not knocked off the table).
  lifted = (gone & (np.asarray(info.picked) > 0) & (np.asarray(info.lost) == 0)).reshape(n, -1)
  return case, lifted


def ordered_case(path, base) -> dict:
  case, lifted = lift_table(path, base, base.env.num_rotations // 2)
  xy = np.array([o.pos[:2] for o in case.objects])
  gap = np.linalg.norm(xy[:, None] - xy[None], axis=-1) + np.eye(len(xy)) * 1e9
  packed = gap.min(axis=1) < PACKED
  objects = [dict(shape=o.shape, line=o.line, packed=bool(p), lifted_at=np.flatnonzero(r).tolist())
             for o, p, r in zip(case.objects, packed, lifted)]
  liftable = lifted.any(axis=1)
  return dict(case=case.name, objects=objects,
              packed=int(packed.sum()), packed_liftable=int((liftable & packed).sum()),
              isolated_liftable=f'{int((liftable & ~packed).sum())}/{int((~packed).sum())}')


def isolated_case(path, base) -> dict:
  case, lifted = lift_table(path, base, base.env.num_rotations)
  return dict(case=case.name, shape=case.objects[0].shape, rotations_lifted=int(lifted.sum()))


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  config_lib.add_arguments(parser)
  parser.add_argument('--cases', nargs='*', default=None,
                      help='ordered case numbers to run, e.g. 00 02 (default: all six)')
  args = parser.parse_args()
  runtime.setup()
  base = config_lib.from_arguments(args)
  files = suite_files(['dev-ordered', 'isolated'])
  paths = files['dev-ordered']
  if args.cases:
    paths = [p for p in paths if p.stem.rsplit('-', 1)[1] in args.cases]
    if len(paths) != len(set(args.cases)):
      parser.error(f'--cases {" ".join(args.cases)}: dev-ordered has cases 00 to 05')
  t0 = time.perf_counter()
  results = [ordered_case(p, base) for p in paths]
  control = [isolated_case(p, base) for p in files['isolated']]
  packed = sum(r['packed'] for r in results)
  liftable = sum(r['packed_liftable'] for r in results)
  print(json.dumps(dict(
      benchmark='ordered_graspability',
      settings=dict(contact_timeconst=base.scene.contact_timeconst, timestep=base.scene.timestep,
                    rotations=f'{base.env.num_rotations // 2} of {base.env.num_rotations} '
                              '(half turn); isolated shapes: all',
                    grasp_depth=base.env.grasp_depth, backend=jax.default_backend(),
                    machine=platform.machine(), cpu_count=os.cpu_count(), jax=jax.__version__,
                    overrides=args.overrides),
      cases=results, isolated=control,
      packed_objects=packed, packed_liftable_without_push=liftable,
      fraction_liftable=round(liftable / max(packed, 1), 3),
      isolated_fewest_rotations=min(r['rotations_lifted'] for r in control),
      seconds_with_compile=round(time.perf_counter() - t0, 1)), indent=1))


if __name__ == '__main__':
  main()
