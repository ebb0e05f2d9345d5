"""Whether settled heaps stay put with nothing touching them, with and without MuJoCo's noslip pass.

Each case of the suites is started as `mvcoba-eval` starts it (settled, jittered, run 0), then
native MuJoCo steps it `--seconds` with the gripper parked. Prints one JSON object: per setting of
`scene.noslip_iterations`, per case, how many objects in play slid more than 1 cm and 5 cm and
how many left the workspace (what an evaluation counts as lost), and the physics time per
simulated second, with its ratio to the first setting measured in the same run.

  python benchmarks/heap_creep.py [--suite dev-random docs/results/validation/val-heaps]
                                  [--noslip 0 3] [--seconds 60]
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import time

import mujoco
import numpy as np
from physics import settings

from mvcoba_jax import runtime
from mvcoba_jax.config import resolve
from mvcoba_jax.sim.scenarios import read_case
from mvcoba_jax.suites import suite_files
from mvcoba_jax.suites.cases import settled_starts


def creep(cases, config, seconds: float) -> dict:
  """Per case: objects that slid > 1 cm and > 5 cm and that left the workspace in `seconds`."""
  env, starts = settled_starts(cases, config, runs=1)
  model = env.scene.mj_model
  data = mujoco.MjData(model)
  qpos_xyz = np.asarray(env.scene.index.slot_qpos)[:, None] + np.arange(3)
  half = config.scene.workspace_half
  rows, physics_s = {}, 0.0
  for i, case in enumerate(cases):
    data.qpos[:], data.qvel[:] = np.asarray(starts.sim.qpos[i]), 0.0
    data.mocap_pos[:], data.mocap_quat[:] = (np.asarray(starts.sim.mocap_pos[i]),
                                             np.asarray(starts.sim.mocap_quat[i]))
    data.ctrl[:] = np.asarray(starts.sim.qpos[i])[np.asarray(env.scene.index.gripper_qpos)]
    mujoco.mj_forward(model, data)
    play = np.asarray(starts.in_play[i])
    before = data.qpos[qpos_xyz].copy()
    t0 = time.perf_counter()
    for _ in range(round(seconds / model.opt.timestep)):
      mujoco.mj_step(model, data)
    physics_s += time.perf_counter() - t0
    after = data.qpos[qpos_xyz]
    slid = np.linalg.norm(after[play, :2] - before[play, :2], axis=1)
    left = (np.abs(after[play, :2]) > half).any(axis=1)
    rows[case.name] = {'objects': int(play.sum()), 'slid_1cm': int((slid > 0.01).sum()),
                       'slid_5cm': int((slid > 0.05).sum()), 'left': int(left.sum()),
                       'top_z': round(float(before[play, 2].max()), 3)}
  total = {k: sum(r[k] for r in rows.values()) for k in ('objects', 'slid_1cm', 'slid_5cm', 'left')}
  return {'cases': rows, 'total': total,
          'physics_s_per_sim_s': physics_s / (seconds * len(cases))}


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--suite', nargs='+', default=['dev-random',
                                                     'docs/results/validation/val-heaps'])
  parser.add_argument('--noslip', type=int, nargs='+', default=[0, 3])
  parser.add_argument('--seconds', type=float, default=60.0)
  args = parser.parse_args()
  runtime.setup()
  base = resolve('default', ['scene.backend=native'])
  out = {'settings': {**settings(), 'suites': args.suite, 'seconds': args.seconds,
                      'noslip': args.noslip, 'preset': 'default'}, 'results': {}}
  for suite, files in suite_files(args.suite).items():
    cases = [read_case(f) for f in files]
    for n in args.noslip:
      config = dataclasses.replace(
          base, scene=dataclasses.replace(base.scene, noslip_iterations=n))
      out['results'].setdefault(suite, {})[n] = creep(cases, config, args.seconds)
    first = out['results'][suite][args.noslip[0]]['physics_s_per_sim_s']
    for n in args.noslip:
      row = out['results'][suite][n]
      row['physics_time_ratio'] = row['physics_s_per_sim_s'] / first
  print(json.dumps(out, indent=1))


if __name__ == '__main__':
  main()
