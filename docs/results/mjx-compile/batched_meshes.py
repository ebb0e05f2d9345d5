"""Issue 69: MJX's collision step with convex meshes batched, one collision function per pair of
geom types and class of meshes rather than per pair of meshes; measured, not adopted
(docs/results/mjx-compile.md, "Batching the convex meshes").

MJX traces a collision function for every group of geom pairs that share geom types and mesh ids
(`collision_driver._geom_groups`), since its convex functions take a mesh's shape as static; the
scene's four convex meshes make 15 of its 17 groups. Here the meshes of a class are padded to one
shape by repeating a vertex, face or edge after their own, which MJX's convex functions pass over
(they take maxima and minima over them, and the first index of a tie), stacked, and each pair
gathers its own. MJX's groups are kept for everything else: each is culled to `max_geom_pairs` as
MJX culls it, the culled mesh groups of one pair of types and classes go through one call, and
the contacts come back in MJX's order. `collision` replaces MJX's `collision_driver.collision`
while a program traces (`batched_meshes`).

Compiles a 100-step scan of `mjx.step` at 8 tabletops dropped and settled by native MuJoCo, runs
it, and prints the largest qpos difference from MJX's own collision step (run `plain` first):

  JAX_ENABLE_COMPILATION_CACHE=false python docs/results/mjx-compile/batched_meshes.py VARIANT
  VARIANT: plain (MJX's), each (every mesh its own class: MJX's groups through this driver),
           shapes (the cylinder and disk, of one shape, as a class), all (one class),
           meshpairs (one class, only in the mesh-mesh pairs)
"""
from __future__ import annotations

import contextlib
import inspect
import json
import pathlib
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np
from mujoco.mjx._src import collision_convex, collision_driver, mesh
from mujoco.mjx._src.collision_types import ConvexInfo, GeomInfo
from mujoco.mjx._src.types import GeomType

MESH_FIELDS = ('vert', 'face', 'face_normal', 'edge', 'edge_face_normal')
# The convex functions of the pairs of types with a mesh that the scene has, unwrapped from
# MJX's per-mesh `collider`.
_RAW = {types: inspect.getclosurevars(fn).nonlocals['collision_fn']
        for types, fn in {(GeomType.PLANE, GeomType.MESH): collision_convex.plane_convex,
                          (GeomType.BOX, GeomType.MESH): collision_convex.convex_convex,
                          (GeomType.MESH, GeomType.MESH): collision_convex.convex_convex}.items()}
NCON = 4  # contacts per pair of each function in `_RAW`


def padded_meshes(model, ids) -> dict[str, np.ndarray]:
  """The convex meshes `ids` of the MJX `model` in one shape, stacked (len(ids), ...) by field:
  vertices, faces, face normals and edges each padded with copies of the first, after the mesh's
  own; each face's vertex list padded with its last vertex, as MJX pads two meshes' faces."""
  meshes = [{f: np.asarray(getattr(model._impl.mesh_convex[i], f)) for f in MESH_FIELDS}
            for i in ids]
  most = {f: max(m[f].shape[0] for m in meshes) for f in MESH_FIELDS}
  face_verts = max(m['face'].shape[1] for m in meshes)
  stacked = {}
  for f in MESH_FIELDS:
    rows = []
    for m in meshes:
      a = m[f]
      if f == 'face':
        a = np.pad(a, ((0, 0), (0, face_verts - a.shape[1]), (0, 0)), 'edge')
      rows.append(np.concatenate([a, np.repeat(a[:1], most[f] - a.shape[0], axis=0)]))
    stacked[f] = np.stack(rows)
  return stacked


def _collide(m, d, types, geom, tables):
  """MJX's `collider` for the pairs `geom` (P, 2) of `types`, each mesh gathered per pair from
  its side's table (`Classes.tables`)."""
  infos, axes = [], []
  for side in (0, 1):
    g = geom[:, side]
    info = GeomInfo(d.geom_xpos[g], d.geom_xmat[g], m.geom_size[g])
    axis = 0
    if types[side] == GeomType.BOX:
      info = mesh.box(info)
      axis = jax.tree.map(lambda _: None, info).replace(pos=0, mat=0, size=0, face=0, vert=0)
    elif types[side] == GeomType.MESH:
      table, local = tables[side]
      ids = jnp.asarray(local[np.asarray(m.geom_dataid)])[g]
      info = ConvexInfo(**vars(info), **{f: jnp.asarray(table[f])[ids] for f in MESH_FIELDS})
    infos.append(info)
    axes.append(axis)
  dist, pos, frame = jax.vmap(_RAW[types], in_axes=axes)(*infos)
  return jax.tree.map(jnp.concatenate, (dist, pos, frame))


class Classes:
  """Meshes batched together: `groups` lists the mesh ids of each class, in the pairs of geom
  types `types` (the others as MJX groups them)."""

  def __init__(self, model, groups, types=tuple(_RAW)):
    self.types = types
    self.of = {i: c for c, ids in enumerate(groups) for i in ids}
    self.tables = [padded_meshes(model, ids) for ids in groups]
    self.local = np.full(model.nmesh, -1)
    for ids in groups:
      self.local[list(ids)] = np.arange(len(ids))

  def key(self, key):
    return tuple(self.of.get(int(i)) for i in key.data_ids)

  def side_tables(self, key):
    return [(self.tables[c], self.local) if c is not None else None for c in self.key(key)]


def collision(m, d, classes: Classes):
  """`collision_driver.collision` of MJX (mujoco-mjx 3.17, the pinned version), its mesh groups batched."""
  if d._impl.ncon == 0:
    return d
  max_geom_pairs = collision_driver._numeric(m, 'max_geom_pairs')
  max_contact_points = collision_driver._numeric(m, 'max_contact_points')
  groups = collision_driver._contact_groups(m, d)
  for key, contact in groups.items():  # MJX's broad phase, per group
    if (max_geom_pairs > -1 and contact.geom.shape[0] > max_geom_pairs
        and not set(key.types) & collision_driver._GEOM_NO_BROADPHASE):
      pos1, pos2 = d.geom_xpos[contact.geom.T]
      size1, size2 = m.geom_rbound[contact.geom.T]
      dist = jax.vmap(jnp.linalg.norm)(pos2 - pos1) - (size1 + size2)
      _, idx = jax.lax.top_k(-dist, k=max_geom_pairs)
      groups[key] = jax.tree.map(lambda x, idx=idx: x[idx], contact)

  calls = {}  # the groups each call collides: a mesh group's pairs with its types' others
  for key in groups:
    calls.setdefault((key.types, key.condim, classes.key(key)) if key.types in classes.types
                     else key, []).append(key)
  for keys in calls.values():
    types = keys[0].types
    if types in classes.types:
      geom = jnp.concatenate([groups[k].geom for k in keys])
      out, ncon = _collide(m, d, types, geom, classes.side_tables(keys[0])), NCON
    else:
      func = collision_driver._COLLISION_FUNC[types]
      out, ncon = func(m, d, keys[0], groups[keys[0]].geom), func.ncon
    start = 0
    for k in keys:
      rows = groups[k].geom.shape[0] * ncon
      dist, pos, frame = (x[start:start + rows] for x in out)
      start += rows
      contact = groups[k]
      if ncon > 1:
        contact = jax.tree.map(lambda x, r=ncon: jnp.repeat(x, r, axis=0), contact)
      groups[k] = contact.replace(dist=dist, pos=pos, frame=frame)

  condim_groups = {}  # as MJX: grouped by condim, capped, concatenated
  for key, contact in groups.items():
    condim_groups.setdefault(key.condim, []).append(contact)
  if max_contact_points > -1:
    for key, contacts in condim_groups.items():
      contact = jax.tree.map(lambda *x: jnp.concatenate(x), *contacts)
      if contact.geom.shape[0] > max_contact_points:
        _, idx = jax.lax.top_k(-contact.dist, k=max_contact_points)
        contact = jax.tree.map(lambda x, idx=idx: x[idx], contact)
      condim_groups[key] = [contact]
  contacts = sum([condim_groups[k] for k in sorted(condim_groups)], [])
  contact = jax.tree.map(lambda *x: jnp.concatenate(x), *contacts)
  return d.tree_replace({'_impl.contact': contact})


@contextlib.contextmanager
def batched_meshes(classes: Classes):
  """MJX's forward pass collides with `collision` over `classes` meanwhile: wrap the tracing of
  `mjx.step`."""
  original = collision_driver.collision
  collision_driver.collision = lambda m, d: collision(m, d, classes)
  try:
    yield
  finally:
    collision_driver.collision = original


VARIANTS = {'each': [[0], [1], [2], [3]], 'shapes': [[0, 1], [2], [3]], 'all': [[0, 1, 2, 3]],
            'meshpairs': [[0, 1, 2, 3]]}  # meshpairs: only the mesh-mesh pairs batched
MESH_PAIRS = ((GeomType.MESH, GeomType.MESH),)


def main(which: str, batch: int = 8, steps: int = 100):
  from mujoco import mjx

  from mvcoba_jax.config import resolve
  from mvcoba_jax.sim.mjx_physics import MjxPhysics
  from mvcoba_jax.sim.tabletop import Tabletop
  env = Tabletop(resolve(None, ['scene.backend=native']).tabletop)
  states = jax.jit(jax.vmap(env.reset))(jax.random.split(jax.random.PRNGKey(0), batch))
  physics = MjxPhysics(env.scene, env._parking)
  mx = physics.model
  data = jax.vmap(physics._data)(states.sim)

  def run(d):
    step = lambda d, _: (jax.vmap(mjx.step, in_axes=(None, 0))(mx, d), None)
    return jax.lax.scan(step, d, None, length=steps)[0]
  context = (contextlib.nullcontext() if which == 'plain'
             else batched_meshes(Classes(mx, VARIANTS[which],
                                         MESH_PAIRS if which == 'meshpairs' else tuple(_RAW))))
  start = time.perf_counter()
  with context:
    lowered = jax.jit(run).lower(data)
  lower_s = time.perf_counter() - start
  start = time.perf_counter()
  compiled = lowered.compile()
  compile_s = time.perf_counter() - start
  jax.block_until_ready(compiled(data))
  start = time.perf_counter()
  out = jax.block_until_ready(compiled(data))
  run_s = time.perf_counter() - start
  where = f'/tmp/batched-meshes-{which}.npy'
  np.save(where, np.asarray(out.qpos))
  plain = pathlib.Path('/tmp/batched-meshes-plain.npy')
  gap = float(np.abs(np.load(plain) - np.asarray(out.qpos)).max()) if plain.exists() else None
  print(json.dumps({'variant': which, 'classes': VARIANTS.get(which), 'batch': batch,
                    'steps': steps, 'lower_s': round(lower_s, 1), 'compile_s': round(compile_s, 1),
                    'run_s': round(run_s, 2), 'max_qpos_gap_from_plain': gap}), file=sys.stdout)


if __name__ == '__main__':
  main(sys.argv[1])
