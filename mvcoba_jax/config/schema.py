"""The config's schema: the frozen dataclasses of perception, network and training beside the
simulator's (`sim/config.py`), each field checked when built, and the limits `validate` holds a
whole config to."""
from __future__ import annotations

import dataclasses

from mvcoba_jax.sim.config import (
  Between,
  CameraConfig,
  ConfigError,
  EnvConfig,
  Error,
  GripperConfig,
  SceneConfig,
  TabletopConfig,
  check,
)
from mvcoba_jax.sim.contract import RANGES

__all__ = ['CameraConfig', 'Config', 'ConfigError', 'EnvConfig', 'Error', 'GripperConfig',
           'NetworkConfig', 'PerceptionConfig', 'SceneConfig', 'TabletopConfig', 'TrainConfig']


TRUNKS = ('small', 'densenet121')
TARGETS = ('network', 'acting')  # train.target
FUTURE_MAX = ('rule', 'both')  # train.future_max


@dataclasses.dataclass(frozen=True)
class PerceptionConfig:
  """Heightmaps and change observation."""
  heightmap_resolution: float = 0.004  # m per cell: 112 x 112 (the paper: 0.002 -> 224 x 224)
  # Change is observed when more cells than `change_area` / resolution^2 changed height by
  # between `change_min` and `change_max`: VPG's 300 cells at 2 mm, the same area at any grid.
  change_area: float = 300 * 0.002 ** 2
  change_min: float = 0.01
  change_max: float = 0.3
  # Beyond the paper, off in its rule: a grasp that held nothing counts as no change whatever it
  # moved, so the change rule pushes next instead of grasping again at the nudged pile.
  failed_grasp_changes: bool = True
  # With `failed_grasp_changes` off, after each of the first `failed_grasp_retries` grasps in a
  # row that held nothing but moved the scene the rule grasps again, pushing after the next; the
  # reward and targets still count them as no change (a failed grasp keeps its zero future). On
  # a heap a push after a failed grasp shoves neighbours over the border, where a second grasp
  # may hold.
  failed_grasp_retries: int = 0
  # Beyond the paper: each view's unseen cells (an occluder's shadow) take the highest point the
  # other views saw there, and its colour, before anything reads the heightmaps; `seen` stays
  # what each camera saw.
  fill_unseen: bool = False

  def __post_init__(self):
    check(self, 'perception.', {name: Between(*RANGES[f'perception.{name}']) for name in (
        'heightmap_resolution', 'change_area', 'failed_grasp_retries', 'change_min',
        'change_max')})


@dataclasses.dataclass(frozen=True)
class NetworkConfig:
  """The Q-network. `method` picks the architecture and the action rule."""
  method: str = 'mvcoba'  # a method of mvcoba_jax/methods.py
  trunk: str = 'small'  # 'small' (CPU-sized, from scratch) or 'densenet121' (GPU-sized)
  stem_patch: int = 4  # the stem turns patch x patch cells into one feature vector
  features: tuple[int, ...] = (32, 64, 64)  # channels of the trunk stages (small trunk)
  groups: int = 8  # GroupNorm groups
  # Pad the heightmaps to their diagonal before turning them, as the authors' code does, so no
  # turn cuts a corner off; costs about 2x the forward. (Their other input change, a 2x zoom,
  # is `stem_patch` halved: a patch over a nearest-neighbour zoom is a patch half the size.)
  pad_to_diagonal: bool = False
  # Stages run once per state before the turn (small trunk): 0 turns the heightmaps and runs the
  # whole FCN per rotation; 1 runs the streams once and turns their feature maps; n > 1 also the
  # trunk's first n - 1 blocks. At least one block runs per rotation, or every turn would score
  # alike. Each FCN's maps are then turned back at the stem's resolution and upsampled.
  shared_stages: int = 0
  # The rule compares CPG's suppressed scores (`learner/suppression.py`), as a method that
  # suppresses always does: beyond MV-COBA, whose change rule then picks its primitive's best
  # allowed action.
  suppress: bool = False
  # With suppression: a push is also suppressed where the workspace's border lies less than this
  # far (m) ahead of its start along its direction, so pushes head into the table, not over its
  # edge; 0 allows any direction (CPG).
  push_room: float = 0.0

  def __post_init__(self):
    check(self, 'network.', {'trunk': TRUNKS, 'stem_patch': Between(1, 16),
                             'shared_stages': Between(0, 16), 'push_room': Between(0, 1),
                             'features': Between(1, 4096), 'groups': Between(1, 512)})
    if not self.features:
      raise ConfigError('network.features: at least one stage')
    if self.shared_stages and self.trunk != 'small':
      raise ConfigError(f'network.shared_stages={self.shared_stages} needs network.trunk=small')
    if self.shared_stages >= len(self.features):
      raise ConfigError(f'network.shared_stages={self.shared_stages}: at most '
                        f'{len(self.features) - 1} with network.features={self.features} (one '
                        'block at least runs per rotation)')


@dataclasses.dataclass(frozen=True)
class TrainConfig:
  """Q-learning."""
  total_actions: int = 3000  # counted over all environments
  steps_per_iteration: int = 4  # lockstep actions per call (`Trainer.compiled`)
  learning_rate: float = 1e-4
  momentum: float = 0.9
  weight_decay: float = 2e-5
  gamma: float = 0.5
  huber_delta: float = 1.0
  epsilon_start: float = 0.5
  epsilon_end: float = 0.1
  epsilon_decay_actions: int = 800  # linear decay over this many actions (~25 min on 2 CPU cores)
  explore_min_height: float = 0.01  # random actions go to heightmap cells above this (m)
  replay_capacity: int = 1024  # transitions kept on the device
  batch_size: int = 8  # transitions per SGD update
  # Replayed transitions sampled per new transition. 0: one update per lockstep action, so the
  # ratio is batch_size / num_envs and falls as the batch of tabletops grows; > 0: as many
  # updates per lockstep action as keep it (`updates_per_step`), the same at any num_envs.
  replay_ratio: float = 0.0
  priority_exponent: float = 0.6  # sampling weight |TD error|^alpha (0: uniform)
  target_update_period: int = 50  # SGD updates between target-network copies
  # Where max Q(s') of the bootstrap target comes from: 'acting', the online network's acting
  # forward at s', computed anyway one step later and stored with the transition; 'network' (the
  # paper's), the target network run on each sampled s' at update time. 'acting' trains 1.7x as
  # many actions/s at B=8 and learned as well over 3 seeds (docs/results/learner-throughput.md).
  target: str = 'acting'
  # The learning recipe (the `authors` preset holds the MV-COBA authors' code's values; these
  # defaults are the paper's text): rewards of a failed grasp that changed the scene and of a
  # push that changed nothing; whether an action that changed nothing bootstraps (False: its
  # future is 0, as in VPG's and the authors' code); the future's max over the rule's primitive
  # ('rule') or over both primitives' maps ('both'); every grasp also labelled at its rotation
  # turned half way (a parallel-jaw grasp is the same grasp turned by 180 degrees); each update
  # also trains on the B transitions stored this step, besides `batch_size` replayed ones.
  # Beyond both: `quarter_turns` turns each replayed transition (states and action) by a random
  # multiple of 90 degrees about the heightmap centre, teaching a network whose early stages see
  # the state unturned (`network.shared_stages`) the symmetry that turned heightmaps build in.
  # `lost_object_reward` is added for each object that leaves the workspace during the action (0:
  # the paper's and the authors' rewards, which do not see losses). Down to -3: a push that sends
  # an object off the table changes the heightmap surely, earning 0.5 and a future, so a loss
  # must cost more than a push that changes nothing (`no_change_push_reward`) to be avoided.
  failed_grasp_reward: float = 0.5
  no_change_push_reward: float = 0.0
  lost_object_reward: float = 0.0
  bootstrap_no_change: bool = True
  future_max: str = 'rule'
  grasp_symmetry: bool = False
  fresh_in_batch: bool = False
  quarter_turns: bool = False
  checkpoint_every: int = 25  # host iterations between checkpoints
  curve_window: int = 200  # attempts in the sliding window of the training curves

  def __post_init__(self):
    check(self, 'train.', {
        'total_actions': Between(1, 10 ** 9), 'steps_per_iteration': Between(1, 10000),
        'learning_rate': Between(0, 1, low_open=True), 'momentum': Between(0, 0.999),
        'weight_decay': Between(0, 0.1), 'gamma': Between(0, 0.999),
        'huber_delta': Between(0, 100, low_open=True), 'epsilon_start': Between(0, 1),
        'epsilon_end': Between(0, 1), 'epsilon_decay_actions': Between(1, 10 ** 9),
        'explore_min_height': Between(0, 0.4), 'replay_capacity': Between(1, 10 ** 7),
        'batch_size': Between(1, 4096), 'replay_ratio': Between(0, 64),
        'priority_exponent': Between(0, 10),
        'target_update_period': Between(1, 10 ** 9), 'target': TARGETS,
        'checkpoint_every': Between(1, 10 ** 9), 'failed_grasp_reward': Between(-1, 1),
        'no_change_push_reward': Between(-1, 1), 'lost_object_reward': Between(-3, 0),
        'future_max': FUTURE_MAX,
        'curve_window': Between(1, 10 ** 7)})


@dataclasses.dataclass(frozen=True)
class Config:
  scene: SceneConfig = SceneConfig()
  env: EnvConfig = EnvConfig()
  perception: PerceptionConfig = PerceptionConfig()
  network: NetworkConfig = NetworkConfig()
  train: TrainConfig = TrainConfig()
  num_envs: int = 8
  seed: int = 0

  def __post_init__(self):
    check(self, '', {'num_envs': Between(1, 65536), 'seed': Between(0, 2 ** 31 - 1)})

  @property
  def tabletop(self) -> TabletopConfig:
    """The scene and the episode: what `Tabletop` is built from."""
    return TabletopConfig(scene=self.scene, env=self.env)

  @property
  def actions_per_call(self) -> int:
    """Actions one call of the compiled training iteration takes: every tabletop, K times."""
    return self.num_envs * self.train.steps_per_iteration

  @property
  def actions_trained(self) -> int:
    """What a run of `train.total_actions` trains: whole calls, so up to one call more."""
    return -(-self.train.total_actions // self.actions_per_call) * self.actions_per_call

  @property
  def updates_per_step(self) -> int:
    """SGD updates after each lockstep action: 1, or with `train.replay_ratio` as many batches
    as sample that many replayed transitions per new one (at least 1)."""
    ratio = self.train.replay_ratio
    return 1 if ratio == 0 else max(1, round(ratio * self.num_envs / self.train.batch_size))


# Actions of one evaluation run or greedy check: counters and traces grow with it.
MAX_ACTIONS_LIMIT = 10_000
REPLAY_LIMIT_BYTES = 16 * 2 ** 30  # a replay above this is refused: no CPU here holds it twice
ACTIVATION_LIMIT_BYTES = 32 * 2 ** 30  # rough size of one acting forward's feature maps
DENSENET_GROWTH = 32  # channels each DenseNet layer adds: GroupNorm's groups must divide it
PHASE_LIMIT_S = 30.0  # simulated seconds of one primitive phase or a reset's settling
