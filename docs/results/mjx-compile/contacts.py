"""Issue 69: how much of MJX's physics compile is collision. Counts the collision function groups
MJX traces for the default scene (one per pair of geom types and mesh ids: `_geom_groups`), then
compiles a 100-step scan of `mjx.step` over 8 tabletops with contacts (`contact`), with
MuJoCo's contact flag disabled (`nocontact`), or with every convex mesh geom given the cylinder's
mesh (`onemesh`: not our objects, the group count MJX would trace if its meshes were batched as
one), the persistent cache off.

  JAX_ENABLE_COMPILATION_CACHE=false python docs/results/mjx-compile/contacts.py contact
  JAX_ENABLE_COMPILATION_CACHE=false python docs/results/mjx-compile/contacts.py nocontact
  JAX_ENABLE_COMPILATION_CACHE=false python docs/results/mjx-compile/contacts.py onemesh
"""
import collections
import re
import json
import sys
import time

import jax
import jax.numpy as jnp
import mujoco
from mujoco import mjx
from mujoco.mjx._src import collision_driver

from mvcoba_jax.config import resolve
from mvcoba_jax.sim.scene import build_mjcf

mjcf = build_mjcf(resolve(None, ['scene.backend=mjx']).scene)
if sys.argv[1] == 'onemesh':
  mjcf = re.sub(r'mesh="(prism|disk|octagon)"', 'mesh="cylinder"', mjcf)
model = mujoco.MjModel.from_xml_string(mjcf)
groups = collision_driver._geom_groups(mjx.put_model(model, impl='jax'))
types = collections.Counter(
    '-'.join(mujoco.mjtGeom(t).name[7:].lower() for t in key.types) for key in groups)
if sys.argv[1] == 'nocontact':
  model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
mx = mjx.put_model(model, impl='jax')
data = jax.vmap(lambda _: mjx.make_data(mx))(jnp.arange(8))


def run(d):
  return jax.lax.scan(lambda d, _: (jax.vmap(mjx.step, in_axes=(None, 0))(mx, d), None), d, None,
                      length=100)[0]


start = time.perf_counter()
lowered = jax.jit(run).lower(data)
lower_s = time.perf_counter() - start
start = time.perf_counter()
lowered.compile()
compile_s = time.perf_counter() - start
print(json.dumps({'which': sys.argv[1], 'groups': len(groups),
                  'pairs': sum(len(v) for v in groups.values()), 'groups_by_types': types,
                  'lower_s': round(lower_s, 1), 'compile_s': round(compile_s, 1)}))
