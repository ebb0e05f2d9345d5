"""A suite's cases in the scene they are evaluated in: the object slots a suite needs and its
config, the load check of its cases, fitting cases written by other simulators, and every run's
settled, jittered start.

The words: a case file (`.scn` or VPG `.txt`) holds one case; a suite is a folder of case files
(or a shipped suite's name, `suites.SUITES`); a layout (`sim.tabletop.Layout`) is what the
simulator places for one run of a case.
"""
from __future__ import annotations

import collections
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from mvcoba_jax.sim.geometry import quat_mul, yaw_quat
from mvcoba_jax.sim.scenarios import (
  ScenarioError,
  case_slots,
  case_to_layout,
  fit_overlaps,
  half_height,
  overlaps,
  read_case,
  stack_layouts,
)
from mvcoba_jax.sim import shapes
from mvcoba_jax.sim.shapes import BLOCK_TABLES
from mvcoba_jax.sim.tabletop import Layout, Tabletop

POSITION_NOISE = 0.002  # m, per axis, on each object's start position
YAW_NOISE = 0.035  # rad (2 deg)


def jitter(layout: Layout, key) -> Layout:
  """The layout with small placement noise on the objects in play (one environment)."""
  k_pos, k_yaw = jax.random.split(key)
  m = layout.in_play.shape[0]
  dxy = jax.random.uniform(k_pos, (m, 2), minval=-POSITION_NOISE, maxval=POSITION_NOISE)
  yaw = jax.random.uniform(k_yaw, (m,), minval=-YAW_NOISE, maxval=YAW_NOISE)
  play = layout.in_play[:, None]
  pos = layout.pos.at[:, :2].add(jnp.where(play, dxy, 0.0))
  quat = jnp.where(play, quat_mul(yaw_quat(yaw), layout.quat), layout.quat)
  return layout.replace(pos=pos, quat=quat)


def start(env: Tabletop, layouts: Layout, keys):
  """The settled start state of each run (N,) from its layout, jittered by its key, and the key
  that run goes on with."""
  k_start, k_loop = jax.vmap(jax.random.split, out_axes=1)(keys)
  return jax.vmap(env.reset_from_case)(jax.vmap(jitter)(layouts, k_start), k_start), k_loop


def pool_for(cases) -> tuple[tuple[str, int], ...]:
  """The smallest object-slot pool that holds every case of a suite."""
  need = collections.Counter()
  for case in cases:
    for shape, count in collections.Counter(o.shape for o in case.objects).items():
      need[shape] = max(need[shape], count)
  return tuple(sorted(need.items()))


def suite_config(config, pool):
  """`config` with the suite's pool and contact limits that grow with it.

  Random drops (`env.num_objects`) play no part in evaluation; they only have to fit the pool.
  """
  slots = sum(n for _, n in pool)
  parts = sum(len(shapes.shape(name).parts) * n for name, n in pool)  # mesh objects: many
  scene = dataclasses.replace(config.scene, pool=pool,
                              max_contact_points=max(config.scene.max_contact_points, 10 * slots),
                              max_geom_pairs=max(config.scene.max_geom_pairs, 2 * slots, parts))
  env = dataclasses.replace(config.env, num_objects=min(config.env.num_objects, slots))
  return dataclasses.replace(config, scene=scene, env=env)


def settled_starts(cases, config, runs: int, seed: int = 0):
  """The environment and the settled start states (len(cases) * runs,) of a suite's runs, exactly
  as `mvcoba-eval --runs runs --seed seed` starts them: same scene, same placement jitter."""
  env = Tabletop(suite_config(config, pool_for(cases)).tabletop)
  layouts = stack_layouts([case_to_layout(c, env) for c in cases for _ in range(runs)])
  keys = jax.random.split(jax.random.PRNGKey(seed), len(cases) * runs)
  return env, jax.jit(lambda l, k: start(env, l, k)[0])(layouts, keys)


SETTLE_MOVE = 0.01  # m: how far an object listed on the table may move while its case settles
ON_TABLE = 0.005  # m: listed within this of its resting height, an object is on the table


def case_problems(cases, config, settle_move: float = SETTLE_MOVE) -> list[str]:
  """What is wrong with `cases` as loaded, in the scene a suite of them gets: one message per
  object, naming its file and line. Objects that interpenetrate as placed; then, in the cases
  with none, objects that leave the workspace while the case settles as written, and objects
  listed on the table that move more than `settle_move` (objects set down on others settle onto
  the heap). Raises ScenarioError for a case that does not fit the scene (occluder slots)."""
  env = Tabletop(suite_config(config, pool_for(cases)).tabletop)
  layouts = [case_to_layout(case, env) for case in cases]
  problems = [overlaps(case, env) for case in cases]
  clean = [i for i, p in enumerate(problems) if not p]
  if clean:
    layouts = [layouts[i] for i in clean]
    states = jax.jit(jax.vmap(env.reset_from_case))(stack_layouts(layouts))
    in_play = np.asarray(states.in_play)
    listed = np.stack([np.asarray(layout.pos) for layout in layouts])
    moved = np.linalg.norm(np.asarray(jax.vmap(env.object_positions)(states))[..., :2]
                           - listed[..., :2], axis=-1)
    for row, i in enumerate(clean):
      case = cases[i]
      for slot, obj in zip(case_slots(case, env), case.objects):
        where = f'{case.path}:{obj.line}: the {obj.shape}'
        if not in_play[row, slot]:
          problems[i].append(f'{where} left the workspace while the case settled')
        elif (abs(obj.pos[2] - half_height(obj.shape, obj.quat)) < ON_TABLE
              and moved[row, slot] > settle_move):
          problems[i].append(f'{where}, listed on the table, moved '
                             f'{100 * moved[row, slot]:.1f} cm while the case settled')
  return [m for p in problems for m in p]


def fitted(cases, config, bound: float):
  """(`cases` each made physically valid by `fit_overlaps` in the scene a suite of them gets,
  each case's objects' moves in m); ScenarioError names every object that would move more than
  `bound`."""
  env = Tabletop(suite_config(config, pool_for(cases)).tabletop)
  done, moves, stuck = [], [], []
  for case in cases:
    try:
      fit, moved = fit_overlaps(case, env, bound)
    except ScenarioError as e:
      stuck.append(str(e))
      continue
    done.append(fit)
    moves.append(moved)
  if stuck:
    raise ScenarioError('\n'.join(stuck))
  return done, moves


def other_block_table(files, config, blocks: str) -> str:
  """A hint for VPG-format case files that overlap: when another block table reads them with
  fewer than half the overlapping pairs, the likely cause is a table that does not match the
  files, and the line says which to try; else empty."""
  files = [f for f in files if f.suffix == '.txt']
  if not files:
    return ''
  half, top = config.scene.workspace_half, config.scene.workspace_top

  def count(table):
    try:
      cases = [read_case(f, half, top, table) for f in files]
    except ScenarioError:  # a mesh the table does not name
      return None
    env = Tabletop(suite_config(config, pool_for(cases)).tabletop)
    return sum(len(overlaps(case, env)) for case in cases)

  here = count(blocks)
  others = {t: n for t in BLOCK_TABLES if t != blocks and (n := count(t)) is not None}
  best = min(others, key=others.get, default=None)
  if not here or best is None or others[best] * 2 > here:
    return ''
  return (f'these files overlap in {here} pairs read with --blocks {blocks} and in '
          f'{others[best]} with --blocks {best}: they are likely {best}\'s block set')
