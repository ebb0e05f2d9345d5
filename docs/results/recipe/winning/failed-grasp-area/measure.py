"""Record script (winning-policy.md, "How much a failed grasp moves"): the area that each
failed grasp and each push of a frozen policy moved, on one validation suite, as the change
observation measures it (cells whose height changed by 1-30 cm, seen in both frames, the larger
of the two views), in cm^2; the change threshold is `perception.change_area` (12 cm^2).

  python docs/results/recipe/winning/failed-grasp-area/measure.py SUITE_FOLDER WORKDIR...

It wraps `Task.step` to report each action's moved area to the host (jax.debug.callback); runs
on emptied tables are left out."""
import json
import sys

import jax
import jax.numpy as jnp
import numpy as np

from mvcoba_jax import api
from mvcoba_jax.sim.contract import moved_cells
from mvcoba_jax.learner import agent
from mvcoba_jax.learner import task as task_lib

records = []
plain_step = task_lib.Task.step


def _record(primitive, success, area, in_play):
  records.extend(zip(*(np.asarray(a).tolist() for a in (primitive, success, area, in_play))))


def measured_step(self, state, action, per_env=task_lib._whole):
  after, out = plain_step(self, state, action, per_env)
  p = self.perception
  cells = moved_cells(state.obs.depth, state.obs.seen, after.obs.depth, after.obs.seen,
                      p.change_min, p.change_max, jnp)
  area = cells.max(axis=-1) * p.heightmap_resolution ** 2
  jax.debug.callback(_record, action.primitive, out.info.grasp_success, area,
                     jnp.sum(state.env.in_play, axis=1))
  return after, out


def main(suite: str, workdirs: list[str]) -> None:
  task_lib.Task.step = measured_step
  name = suite.rstrip('/').split('/')[-1]
  for workdir in workdirs:
    records.clear()
    api.evaluate([workdir], [suite], runs=1, out=f'/tmp/failed-grasp-area-{name}',
                 overwrite=True, progress=False)
    r = np.array([x for x in records if x[3] > 0], float)
    for what, sel in (('failed grasp', (r[:, 0] == agent.GRASP) & (r[:, 1] == 0)),
                      ('push', r[:, 0] == agent.PUSH)):
      cm2 = r[sel, 2] * 1e4
      print(json.dumps({'suite': name, 'workdir': workdir, 'what': what, 'n': int(sel.sum()),
                        'percentiles_10_25_50_75_90_cm2':
                        np.percentile(cm2, [10, 25, 50, 75, 90]).round(1).tolist()
                        if len(cm2) else []}), flush=True)


if __name__ == '__main__':
  main(sys.argv[1], sys.argv[2:])
