"""The contract between the heightmaps, the simulator and the robot: how camera points are binned
into heightmaps, how views fill each other and when they changed, where a heightmap cell is in the
workspace and how far a push slides. One rule each for the simulator (over jax.numpy in the
compiled step: `perception`, `primitives.target`), `Policy.act`, the exported policy's runtime
(`deploy`, numpy only) and the examples, so a policy's figures describe what a robot sees and
does. Imports neither JAX, MuJoCo nor OpenCV: the deploy package reads it without them."""
from __future__ import annotations

import numpy as np

HEIGHT_UNIT = 1e-5  # m: heights are kept in these steps
BELOW_TABLE = -0.005  # m: points lower than this are not the table's

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


def world_to_pixel(x, y, resolution: float, workspace_half: float, xp=np):
  """Heightmap (row, col) of the cell that holds the workspace point (x, y) (may be out of
  range): the inverse of `pixel_to_world`."""
  col = xp.floor((x + workspace_half) / resolution).astype(xp.int32)
  row = xp.floor((y + workspace_half) / resolution).astype(xp.int32)
  return row, col


def binned(x, y, z, hit, resolution: float, workspace_half: float, top: float, xp=np):
  """Each camera point's heightmap cell (row * side + col; -1 for a point outside the grid,
  below BELOW_TABLE or above `top`, or not `hit`) and its height in HEIGHT_UNITs (clipped to
  [0, top]): how the simulator's cameras and a robot's are binned alike, each heightmap cell then
  keeping its highest point."""
  side = round(2 * workspace_half / resolution)
  row, col = world_to_pixel(x, y, resolution, workspace_half, xp)
  keep = (hit & (row >= 0) & (row < side) & (col >= 0) & (col < side) & (z >= BELOW_TABLE)
          & (z <= top))
  cell = xp.where(keep, row * side + col, -1)
  height = xp.round(xp.clip(z, 0.0, top) / HEIGHT_UNIT).astype(xp.int32)
  return cell, height


def pixel_to_world(row, col, resolution: float, workspace_half: float):
  """Centre (x, y) of heightmap cell (row, col): row grows with y, col with x, and cell (r, c)
  covers the square whose lower corner is (-half + c * res, -half + r * res). Over numbers,
  numpy or JAX arrays alike."""
  x = -workspace_half + (col + 0.5) * resolution
  y = -workspace_half + (row + 0.5) * resolution
  return x, y


def filled(color, depth, seen, xp=np):
  """(color, depth) of views (V, R, R[, 3]) whose unseen cells take the highest point any other
  view saw there, with its colour (`perception.fill_unseen`); cells no view saw stay 0. `xp` is
  numpy here and jax.numpy in training (`perception.observe`): one rule on both sides."""
  best = xp.argmax(xp.where(seen, depth, -1.0), axis=0)[None]  # (1, R, R): the highest view
  any_seen = xp.any(seen, axis=0)
  fill_depth = xp.where(any_seen, xp.take_along_axis(depth, best, axis=0)[0], 0.0)
  fill_color = xp.where(any_seen[..., None],
                        xp.take_along_axis(color, best[..., None], axis=0)[0], 0.0)
  return (xp.where(seen[..., None], color, fill_color[None]).astype(color.dtype),
          xp.where(seen, depth, fill_depth[None]).astype(depth.dtype))


def moved_cells(before_depth, before_seen, after_depth, after_seen, change_min: float,
                change_max: float, xp=np):
  """(..., V) how many cells of each view's heightmap (..., V, R, R) changed height by between
  `change_min` and `change_max`, cells missing from either frame counting as unchanged (VPG's
  rule). Over numpy (a robot) or jax.numpy (`perception.frames_changed`)."""
  diff = xp.abs(after_depth - before_depth)
  moved = (diff >= change_min) & (diff <= change_max) & before_seen & after_seen
  return moved.sum(axis=(-2, -1))


def changed_views(before_depth, before_seen, after_depth, after_seen, change_min: float,
                  change_max: float, change_area: float, resolution: float, xp=np):
  """(..., V) whether each view's heightmap (..., V, R, R) changed: more `moved_cells` than
  `change_area` / resolution^2 (VPG's 300 cells at 2 mm)."""
  return (moved_cells(before_depth, before_seen, after_depth, after_seen, change_min, change_max,
                      xp) > change_area / resolution ** 2)


def observed_change(frames_changed, is_grasp, held, failures, failed_grasp_changes: bool,
                    retries, xp=np):
  """(changed, rule_changed) after an action, for the simulator (over jax.numpy) and a robot
  alike. `changed`, which the reward and the failure count read: the frames changed (some view's
  `changed_views`) or a grasp held something (`held`); a policy trained with
  `failed_grasp_changes` off counts a grasp that held nothing as no change whatever it moved.
  `rule_changed`, the `changed` its next action is chosen with: the same, except that after a
  grasp that held nothing the frames still decide while fewer than `retries` failed actions came
  in a row before it (`failures`, as `failures_after` counts them)."""
  frames_changed, is_grasp, held = (xp.asarray(v, bool) for v in (frames_changed, is_grasp, held))
  changed = frames_changed | (is_grasp & held)
  if failed_grasp_changes:
    return changed, changed
  kept = ~is_grasp | held
  return changed & kept, changed & (kept | (failures < retries))


def failed(is_grasp, held, changed, xp=np):
  """An action that achieved nothing: a grasp that held nothing, a push that changed nothing
  (`changed` as `observed_change` gives it)."""
  return xp.where(xp.asarray(is_grasp, bool), ~xp.asarray(held, bool), ~xp.asarray(changed, bool))


def failures_after(failures, is_grasp, held, changed, xp=np):
  """The failed actions in a row once this one is done: a `failed` one adds one, anything else
  starts again at 0. The count that ends a run (`env.max_failures`) and that `observed_change`
  reads."""
  return xp.where(failed(is_grasp, held, changed, xp), failures + 1, 0)
