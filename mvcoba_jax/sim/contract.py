"""The contract between the heightmaps, the simulator and the robot: where a heightmap cell is in
the workspace and how far a push slides. One rule each for the simulator (`primitives.target`,
over jax.numpy in the compiled step), `Policy.act`, the exported policy's runtime
(`deploy.OnnxPolicy.act`, numpy only) and the examples, so a policy's figures describe the actions
a robot takes. Imports neither JAX nor MuJoCo: the deploy package reads it without them."""
from __future__ import annotations

import numpy as np

# The primitives' numbers: the order of the networks' maps and of the exported graph's action.
PUSH, GRASP = 0, 1

# The ranges (closed) of the settings an export carries to a robot, checked alike by the configs
# that train and evaluate with them (`sim.config.Between`) and by model.json's reader
# (`deploy.model_file`), so neither holds a value the other refuses.
RANGES = {
    'env.num_rotations': (1, 64),
    'env.push_length': (0.001, 1.0),  # m
    'scene.workspace_half': (0.05, 1.0),  # m
    'scene.gripper.max_opening': (0.01, 0.3),  # m
    'perception.heightmap_resolution': (0.0005, 0.05),  # m per cell
    'perception.change_min': (0.0, 1.0),  # m
    'perception.change_max': (0.0, 1.0),  # m
    'perception.change_area': (1e-6, 1.0),  # m^2
    'perception.failed_grasp_retries': (0, 100),
}


def push_length(start, angle, length, half, xp=np):
  """How far a push from `start` (x, y) along `angle` (both in the workspace frame) slides, up to
  `length`, and ends within +-half: cut short at the workspace's edge, as VPG's robot code cuts
  it, so no push sweeps past the region the cameras were calibrated on. Over numpy (the default)
  or `xp=jax.numpy` inside a traced program."""
  reach = length
  for at, step in zip(start, (xp.cos(angle), xp.sin(angle))):
    along = xp.abs(step) > 1e-12
    border = xp.where(step > 0, half, -half)
    reach = xp.where(along, xp.minimum(reach, (border - at) / xp.where(along, step, 1.0)), reach)
  return xp.maximum(reach, 0.0)


def pixel_to_world(row, col, resolution: float, workspace_half: float):
  """Centre (x, y) of heightmap cell (row, col): row grows with y, col with x, and cell (r, c)
  covers the square whose lower corner is (-half + c * res, -half + r * res). Over numbers,
  numpy or JAX arrays alike."""
  x = -workspace_half + (col + 0.5) * resolution
  y = -workspace_half + (row + 0.5) * resolution
  return x, y
