"""Data parallelism over all local devices: environments and replay sharded, parameters replicated.

The training step is written for one device; placing its state with these shardings lets XLA
partition it (GSPMD): each device steps its share of the environments (`Trainer.per_env`) and
holds its share of the replay, and the loss, a mean over the sampled batch, gets its gradients
averaged across devices by the compiler. The step's outputs must come back with the shardings
they went in with, or every call compiles the step again. On one CPU,
`XLA_FLAGS=--xla_force_host_platform_device_count=N` makes N virtual devices.
"""
from __future__ import annotations

import jax
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from mvcoba_jax.learner.training import TrainState


def mesh(devices=None) -> Mesh:
  return Mesh(np.asarray(devices if devices is not None else jax.devices()), ('data',))


def state_shardings(state: TrainState, mesh_: Mesh) -> TrainState:
  """Shardings for every leaf: per-environment and replay arrays split on their first axis."""
  split = NamedSharding(mesh_, PartitionSpec('data'))
  whole = NamedSharding(mesh_, PartitionSpec())
  n = mesh_.devices.size

  def along_first(tree):  # zero-size arrays come out of a jitted step replicated: keep them so
    return jax.tree.map(lambda x: split if x.size and x.shape[0] % n == 0 else whole, tree)

  everything = jax.tree.map(lambda _: whole, state)
  return everything.replace(
      task=along_first(state.task),
      pending=along_first(state.pending),
      reserve=everything.reserve.replace(states=along_first(state.reserve.states)),
      replay=everything.replay.replace(data=along_first(state.replay.data),
                                       priority=along_first(state.replay.priority)))


def check_divisible(num_envs: int, mesh_: Mesh) -> None:
  n = mesh_.devices.size
  if num_envs % n:
    raise ValueError(f'num_envs={num_envs} does not split over {n} devices; use a multiple of {n}')


def place(state: TrainState, mesh_: Mesh) -> TrainState:
  """The state on the mesh's devices with the data-parallel shardings."""
  return jax.device_put(state, state_shardings(state, mesh_))
