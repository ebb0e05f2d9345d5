"""Configuration of the simulated tabletop: the compiled scene, its cameras and the episode.

The training configuration (`mvcoba_jax.config.Config`) holds these as its `scene` and `env`;
the simulator itself needs only an object with those two fields (`TabletopConfig`).
"""
from __future__ import annotations

import dataclasses
from typing import Protocol


class ConfigError(ValueError):
  """A preset, override or saved config that does not fit the configuration schema."""


@dataclasses.dataclass(frozen=True)
class CameraConfig:
  """A pinhole RGB-D camera looking from `pos` at `target`."""
  pos: tuple[float, float, float]
  target: tuple[float, float, float] = (0.0, 0.0, 0.0)
  width: int = 160
  height: int = 160
  fovy_deg: float = 38.0


@dataclasses.dataclass(frozen=True)
class SceneConfig:
  """What goes into the compiled MuJoCo model, and which engine steps it."""
  # 'native': MuJoCo's C engine and mj_ray on CPU threads; 'mjx': MJX, traced into the jitted
  # program (the path for GPUs and TPUs); 'auto': native when JAX's default device is a CPU.
  backend: str = 'auto'
  native_threads: int = 0  # threads of the native backend; 0: every core this process may use
  # Object slots: (shape name, count). Objects not in play are parked away from the table.
  # The default holds every public VPG test case and leaves a choice for random drops.
  pool: tuple[tuple[str, int], ...] = (
      ('cube', 2), ('tall_box', 2), ('flat_box', 1), ('prism', 2), ('arch', 2),
      ('cylinder', 1), ('disk', 1), ('octagon', 1))
  workspace_half: float = 0.224  # workspace is x, y in [-h, h]
  workspace_top: float = 0.4
  timestep: float = 0.004
  iterations: int = 4
  ls_iterations: int = 6
  # Contact stiffness (MuJoCo solref time constant, s). 2 x timestep, the stiffest MuJoCo allows:
  # with its default 0.02 the fingers press packed blocks millimetres into the table and lift
  # them with no push (benchmarks/ordered_graspability.py).
  contact_timeconst: float = 0.008
  friction: float = 1.0
  finger_friction: float = 1.5
  object_density: float = 500.0
  # MJX only (native MuJoCo has no caps): pairs and contact points kept per step.
  max_geom_pairs: int = 24
  max_contact_points: int = 96
  # Opposite sides of the workspace; at 160 x 160 pixels each sees ~97% of a 112 x 112 grid.
  cameras: tuple[CameraConfig, ...] = (
      CameraConfig(pos=(0.35, 0.0, 0.65)), CameraConfig(pos=(-0.35, 0.0, 0.65)))
  # Occluder slots (box half sizes, thin along x to face the cameras): one that can hide the
  # whole workspace from a camera, two partial ones. Scenarios pose them; unused ones are parked.
  occluders: tuple[tuple[float, float, float], ...] = (
      (0.01, 0.12, 0.12), (0.01, 0.05, 0.05), (0.01, 0.05, 0.05))

  @property
  def num_slots(self) -> int:
    return sum(n for _, n in self.pool)


@dataclasses.dataclass(frozen=True)
class EnvConfig:
  """Episode and primitive parameters."""
  num_objects: int = 10  # objects dropped by reset(key)
  num_rotations: int = 16
  settle_steps: int = 375  # physics steps (1.5 s) for placed or dropped objects to come to rest
  drop_margin: float = 0.06  # keep dropped object centres this far inside the workspace
  layer_height: float = 0.12  # vertical spacing of drop layers
  # Grasp: descend to `grasp_depth` below the surface, close, lift `lift_height`.
  grasp_depth: float = 0.03
  lift_height: float = 0.30
  approach_height: float = 0.08
  descend_speed: float = 0.4
  lift_speed: float = 0.6
  close_time: float = 0.2
  hold_time: float = 0.04
  # Push: fingertips `push_height` above the table, move `push_length` along the direction.
  push_height: float = 0.01
  push_length: float = 0.10
  push_speed: float = 0.25
  min_tip_height: float = 0.005
  # Health: any |qvel| above this (or a non-finite value) marks the environment unhealthy.
  max_qvel: float = 50.0
  # An episode ends after more consecutive failed actions than this, in training (new objects are
  # dropped) and in evaluation (the run ends; the paper's completion rule counts 5).
  max_failures: int = 5


class TabletopConfig(Protocol):
  """What a `Tabletop` reads: the scene and the episode."""
  scene: SceneConfig
  env: EnvConfig
