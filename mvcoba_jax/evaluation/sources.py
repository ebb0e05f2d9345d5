"""The policies an evaluation plays, each resolved once into a `Source`: a trained network (a
training's work directory or an export) in its config with the evaluation's overrides, or a
baseline that needs no training."""
from __future__ import annotations

import dataclasses
from typing import Any

from flax import nnx

from mvcoba_jax import config as config_lib
from mvcoba_jax import policy as policy_lib
from mvcoba_jax.config import Config
from mvcoba_jax.evaluation import runner
from mvcoba_jax.evaluation.protocols import Protocol
from mvcoba_jax.learner import agent

BASELINES = ('heuristic',)  # policies without training (`runner.heuristic_actor`)


@dataclasses.dataclass(frozen=True)
class Source:
  """A policy an evaluation plays, with what its results rows record of it."""
  name: str  # the row's method: the network's method, or baseline:NAME
  config: Config | None = None  # a trained network's, as evaluated; None: the evaluation's
  network: Any = None  # networks.QNetwork; None for a baseline
  path: str | None = None  # the folder it was loaded from
  step: int | None = None  # the checkpoint's action count
  training: dict | None = None  # the config it trained with (`config.trained_as`)
  training_seed: int | None = None

  @property
  def trained(self) -> bool:
    return self.network is not None

  @property
  def views(self) -> tuple[int, ...]:
    """The views whose heights place its actions: its method's (a baseline reads both)."""
    return self.network.method.views if self.trained else (0, 1)

  def settings(self) -> dict:
    """What a results row records of its policy."""
    return {'checkpoint': self.path, 'step': self.step,
            'params': policy_lib.fingerprint(self.network) if self.trained else None,
            'training': self.training, 'training_seed': self.training_seed}

  def actor(self, config: Config, protocol: Protocol) -> runner.Actor:
    """The actor playing this source's runs in `config` under `protocol` (a baseline is
    evaluated frozen only: `evaluate` refuses the others)."""
    if not self.trained:
      return runner.heuristic_actor(config.env.num_rotations)
    if protocol.learns:
      return runner.Online(self.network, config)
    graphdef, params = nnx.split(self.network)
    q_maps = lambda obs: nnx.merge(graphdef, params)(obs.color, obs.depth)
    # `networks.QNetwork` carries its method
    return runner.greedy_actor(q_maps, agent.Decision.of(self.network.method, config),
                               protocol.no_repeat)


def trained(path, overrides=()) -> Source:
  """The policy of a training's work directory or an export, evaluated with `overrides`
  (`config.evaluated`). Raises PolicyError or ConfigError naming what cannot serve."""
  config, network, step = policy_lib.load(path)
  return Source(name=config.network.method, config=config_lib.evaluated(config, overrides),
                network=network, path=str(path), step=step,
                training=config_lib.trained_as(config), training_seed=config.seed)


def baseline(name: str) -> Source:
  """A policy of `BASELINES`."""
  return Source(name=f'baseline:{name}')
