"""How much of each object of a case every camera sees once the case has settled: the measure
behind the occluded suite's promise that every object is seen by at least one camera."""
from __future__ import annotations

import jax
import numpy as np

from mvcoba_jax.sim.scenarios import case_to_layout, stack_layouts
from mvcoba_jax.sim.tabletop import Tabletop
from mvcoba_jax.suites import cases as suite_cases


def visibility(cases, config, seen: float = 0.5) -> list[dict]:
  """Per case: each object's visible fraction per camera (its rays' hits with the case's
  occluders over its hits with them parked), and the lines of the objects no camera sees above
  `seen` and of those only one camera does."""
  env = Tabletop(suite_cases.suite_config(config, suite_cases.pool_for(cases)).tabletop)
  layouts = [case_to_layout(c, env) for c in cases]
  states = jax.jit(jax.vmap(env.reset_from_case))(stack_layouts(layouts))
  origins, directions = env.camera_rays
  cast = jax.jit(jax.vmap(lambda sim: env.backend.cast(sim, origins, directions)[1]))
  park_pos, park_quat = env.parked_occluders()
  mocap = env.scene.index.occluder_mocap
  open_sim = states.sim.replace(
      mocap_pos=states.sim.mocap_pos.at[:, mocap].set(park_pos),
      mocap_quat=states.sim.mocap_quat.at[:, mocap].set(park_quat))
  slot_of_geom = env.scene.index.geom_slot
  hit_slots = [slot_of_geom[np.asarray(g)] for g in (cast(states.sim), cast(open_sim))]
  per_camera = len(origins) // len(env.config.scene.cameras)
  rows = []
  for i, case in enumerate(cases):
    slots = [s for s in np.flatnonzero(np.asarray(layouts[i].in_play))]
    objects = []
    for slot, obj in zip(slots, case.objects):
      fractions = []
      for c in range(len(env.config.scene.cameras)):
        window = slice(c * per_camera, (c + 1) * per_camera)
        blocked, free = (int(np.sum(h[i, window] == slot)) for h in hit_slots)
        fractions.append(blocked / free if free else 0.0)
      objects.append({'line': obj.line, 'shape': obj.shape,
                      'in_play': bool(np.asarray(states.in_play[i, slot])),
                      'visible_fraction': [round(f, 3) for f in fractions]})
    rows.append({
        'case': case.name, 'objects': objects,
        'seen_by_none': [o['line'] for o in objects if max(o['visible_fraction']) < seen],
        'seen_by_one_only': [o['line'] for o in objects
                             if sum(f >= seen for f in o['visible_fraction']) == 1]})
  return rows
