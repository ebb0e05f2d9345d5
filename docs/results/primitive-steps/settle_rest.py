"""Issue 69, item 2: whether a settling drop could end when its objects are at rest.

Settles `n` random drops of the default preset on the native backend for `env.settle_steps`,
recording every step, and prints per rest threshold (linear m/s, angular rad/s, every in-play
object below both): the step after which each drop stays at rest (percentiles), the share
still moving in the last 25 steps and the shapes moving at the end, what a batch of 8 in
lockstep would save (the loop ends when its last drop rests), and how far an object moves
after its drop came to rest. `--condim 6 --rolling R`: the same drops with MuJoCo's rolling
friction on (every geom's contact dimension 6, rolling friction R metres).

  python docs/results/primitive-steps/settle_rest.py 128 > settle-rest.jsonl
"""
import argparse
import collections
import json

import jax
import numpy as np
from mujoco import batch as mjbatch

from mvcoba_jax.config import resolve
from mvcoba_jax.sim.native import NativePhysics
from mvcoba_jax.sim.tabletop import Tabletop

parser = argparse.ArgumentParser()
parser.add_argument('drops', type=int, nargs='?', default=128)
parser.add_argument('--condim', type=int, default=None)
parser.add_argument('--rolling', type=float, default=None)
args = parser.parse_args()
n = args.drops
env = Tabletop(resolve(None, ['scene.backend=native']).tabletop)
drops = jax.jit(jax.vmap(env.drop))(jax.random.split(jax.random.PRNGKey(0), n))
m, index, steps = env.scene.mj_model, env.scene.index, env.config.env.settle_steps
if args.condim is not None:
  m.geom_condim[:] = args.condim
if args.rolling is not None:
  m.geom_friction[:, 2] = args.rolling
in_play = np.asarray(drops.in_play)

b = mjbatch.Batch(m, n, nthread=2)  # loaded as NativePhysics loads a settling call
NativePhysics._load(b, *(np.asarray(x) for x in (drops.sim.qpos, drops.sim.mocap_pos,
                                                 drops.sim.mocap_quat, drops.sim.qvel)))
gravcomp = b.expand('body_gravcomp')
gravcomp[:] = m.body_gravcomp
gravcomp[:, env.backend._slot_bodies] = ~in_play
hold = np.broadcast_to(np.asarray(env._gripper_park, np.float64), (n, steps, 6)).copy()
record = b.rollout(steps, hold, record=('qvel', 'qpos'))

vel = record['qvel'][:, :, np.asarray(index.slot_qvel)[:, None] + np.arange(6)]  # (n, T, M, 6)
lin = np.linalg.norm(vel[..., :3], axis=-1) * in_play[:, None]
ang = np.linalg.norm(vel[..., 3:], axis=-1) * in_play[:, None]
pos = record['qpos'][:, :, np.asarray(index.slot_qpos)[:, None] + np.arange(3)]  # (n, T, M, 3)
for v_rest, w_rest in [(0.005, 0.05), (0.01, 0.1), (0.02, 0.2)]:
  moving = (lin.max(-1) > v_rest) | (ang.max(-1) > w_rest)  # (n, T)
  rest = np.array([np.flatnonzero(row).max() + 1 if row.any() else 0 for row in moving])
  after = np.array([np.linalg.norm(pos[i, -1] - pos[i, min(rest[i], steps - 1)], axis=-1)
                    [in_play[i]].max() for i in range(n)])
  lockstep = rest[:n // 8 * 8].reshape(-1, 8).max(1)
  shapes = collections.Counter(index.slot_shapes[j] for j in np.nonzero(moving[:, -1:] & (
      (lin[:, -1] > v_rest) | (ang[:, -1] > w_rest)))[1])
  print(json.dumps({
      'drops': n, 'settle_steps': steps, 'condim': int(m.geom_condim.max()),
      'rolling_friction': float(m.geom_friction[:, 2].max()), 'v_rest': v_rest, 'w_rest': w_rest,
      'rest_step_p50_p90_max': np.percentile(rest, [50, 90, 100]).tolist(),
      'moving_in_last_25_steps': round(float(moving[:, -25:].any(1).mean()), 3),
      'lockstep_8_steps_saved': round(float(np.mean(steps - lockstep)), 1),
      'moved_after_rest_m_p99_max': [round(float(np.percentile(after, 99)), 4),
                                     round(float(after.max()), 4)],
      'moving_at_the_end_by_shape': dict(shapes.most_common())}), flush=True)
