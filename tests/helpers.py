"""Small builders shared by the tests."""
import jax
import jax.numpy as jnp
import numpy as np

from mvcoba_jax import methods
from mvcoba_jax.config import Config, override, resolve
from mvcoba_jax.learner.task import Task
from mvcoba_jax.sim import shapes
from mvcoba_jax.sim.primitives import Action
from mvcoba_jax.sim.scene import park_position
from mvcoba_jax.sim.tabletop import Layout, Tabletop

BACKENDS = ('native', 'mjx', 'warp')  # physics tests run on each; the rest on the default (auto)


def make_config(preset: str, backend: str = 'auto', *overrides: str) -> Config:
  """The config of `preset` on `backend`, with `key=value` overrides."""
  config = override(resolve(preset), f'scene.backend={backend}')
  for assignment in overrides:
    config = override(config, assignment)
  return config


def make_env(preset: str, backend: str = 'auto', *overrides: str) -> Tabletop:
  """The environment of `preset` on `backend`, with `key=value` overrides."""
  return Tabletop(make_config(preset, backend, *overrides).tabletop)


def make_task(preset: str, backend: str = 'auto', *overrides: str) -> Task:
  """The task of `preset` on `backend`, with `key=value` overrides, through its method's views."""
  config = make_config(preset, backend, *overrides)
  return Task.build(config, methods.get(config.network.method).views)


def layout(env, objects):
  """Layout with `objects` = [(slot, x, y, yaw)] resting on the table; other slots parked."""
  m = env.num_slots
  in_play = np.zeros(m, bool)
  pos = np.array([park_position(i) for i in range(m)], np.float32)
  quat = np.tile(np.array([1, 0, 0, 0], np.float32), (m, 1))
  for slot, x, y, yaw in objects:
    half = 0.5 * shapes.shape(env.scene.index.slot_shapes[slot]).extent[2]
    in_play[slot] = True
    pos[slot] = (x, y, half + 0.001)
    quat[slot] = (np.cos(yaw / 2), 0, 0, np.sin(yaw / 2))
  occ_pos, occ_quat = env.parked_occluders()
  return Layout(in_play=jnp.asarray(in_play), pos=jnp.asarray(pos), quat=jnp.asarray(quat),
                color=jnp.full((m, 3), 0.5), occluder_pos=occ_pos, occluder_quat=occ_quat)


def stack(trees):
  return jax.tree.map(lambda *x: jnp.stack(x), *trees)


def actions(rows):
  """Batched Action from [(primitive, rotation, x, y, z)]."""
  p, r, x, y, z = (np.array(c) for c in zip(*rows))
  return Action(primitive=jnp.asarray(p, jnp.int32), rotation=jnp.asarray(r, jnp.int32),
                x=jnp.asarray(x, jnp.float32), y=jnp.asarray(y, jnp.float32),
                z=jnp.asarray(z, jnp.float32))


def logged_row(successes: list[int]) -> dict:
  """An evaluated policy's row as results.json holds it: per case, one run of 4 grasps of 3
  objects with `successes[case]` of them succeeding."""
  run = lambda s: {'actions': 4, 'grasp_attempts': 4, 'grasp_successes': s, 'objects': 3,
                   'picked': min(s, 3), 'lost': 0, 'completed': s >= 3, 'repeated_failures': 0}
  return {'runs': {f'case-{i:02d}': [run(s)] for i, s in enumerate(successes)}}
