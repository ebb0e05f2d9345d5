"""A robot loop over an exported policy: capture every camera, build the heightmaps, act, check,
execute, observe whether the scene changed, again. `Rig` is the interface to subclass for real
hardware (its `capture` returns each camera's depth in metres and colour as RGB; its `execute`
takes a `mvcoba_jax.deploy.Action` in the robot's base frame); `SimulatedRig` is the simulator
standing in for both, so the loop runs end to end here.

  python examples/robot_loop.py --model EXPORT_DIR [--actions 10] [--seed 0]
                                [--gripper NAME [--other-gripper]]

The loop itself needs numpy, OpenCV and onnxruntime only (`mvcoba_jax.deploy`); the simulated rig
needs JAX and MuJoCo.
"""
from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from mvcoba_jax.deploy import Action, DeployError, OnnxPolicy, calibration_from_dict, heightmaps
from mvcoba_jax.sim.contract import failures_after


class Rig:
  """Cameras and a robot: subclass it for the hardware."""

  def capture(self) -> tuple[list[np.ndarray], list[np.ndarray] | None]:
    """Each camera's depth image in metres (height, width) and its colour image (RGB), or None."""
    raise NotImplementedError

  def execute(self, action: Action) -> bool | None:
    """Moves the robot through the primitive (a grasp closes and lifts, a push slides
    `action.push_length` along `action.angle`);
    after a grasp, whether the gripper holds something (its opening, say), else None."""
    raise NotImplementedError


class SimulatedRig(Rig):
  """The simulator as cameras and robot: a random drop of the policy's training scene."""

  def __init__(self, trained: dict, seed: int = 0, gripper: str | None = None):
    import jax  # noqa: PLC0415 (the simulator's needs, not the loop's)
    from mvcoba_jax import config as config_lib  # noqa: PLC0415
    from mvcoba_jax.sim import cameras  # noqa: PLC0415
    from mvcoba_jax.sim.primitives import Action as SimAction  # noqa: PLC0415
    from mvcoba_jax.sim.tabletop import Tabletop  # noqa: PLC0415
    self.jax, self.cameras, self.sim_action = jax, cameras, SimAction
    config = config_lib.from_dict(trained)  # the policy's training config (model.json's)
    if gripper is not None:  # the robot's own gripper, which may not be the policy's
      config = config_lib.override(config, f'scene.gripper={gripper}')
    self.env = Tabletop(config.tabletop)
    self.state = jax.jit(self.env.reset)(jax.random.PRNGKey(seed))
    self.render = jax.jit(lambda s: cameras.render(self.env, s))
    self.step = jax.jit(self.env.step)
    # base frame = workspace frame
    self.calibration = cameras.calibration(self.env, config.perception.heightmap_resolution)

  def capture(self):
    images = self.render(self.state)
    return ([np.asarray(i.depth, np.float64) for i in images],
            [np.round(np.asarray(i.rgb) * 255).astype(np.uint8) for i in images])

  def execute(self, action: Action) -> bool | None:
    jnp = self.jax.numpy
    x, y, z = action.position
    command = self.sim_action(primitive=jnp.int32(action.primitive == 'grasp'),
                              rotation=jnp.int32(action.rotation), x=jnp.float32(x),
                              y=jnp.float32(y), z=jnp.float32(z))
    self.state, info = self.step(self.state, command)
    return bool(info.grasp_success) if action.primitive == 'grasp' else None

  def objects(self) -> int:
    return int(np.asarray(self.state.in_play).sum())


def run(rig: Rig, policy: OnnxPolicy, calibration, actions: int, say=print) -> list[dict]:
  """`actions` rounds of capture, act and execute; a refused action ends the loop with its
  reason. Returns one record a round."""
  depths, colors = rig.capture()
  frame = heightmaps(depths, calibration, colors)
  changed, records = True, []  # before the first action the scene counts as changed
  failures = 0  # failed actions in a row: a grasp that held nothing, a push that changed nothing
  for i in range(actions):
    try:
      action = policy.act(*frame, changed, calibration)
    except DeployError as e:
      records.append({'round': i, 'refused': str(e)})
      say(json.dumps(records[-1]))
      break
    grasped = rig.execute(action)
    depths, colors = rig.capture()
    after = heightmaps(depths, calibration, colors)
    changed = policy.changed(frame[1:], after[1:], grasped, failures)
    failures = int(failures_after(failures, grasped is not None, bool(grasped), changed))
    frame = after
    records.append({'round': i, 'primitive': action.primitive,
                    'position': [round(v, 4) for v in action.position],
                    'angle': round(action.angle, 4), 'opening': round(action.opening, 4),
                    'changed': changed})
    say(json.dumps(records[-1]))
  return records


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--model', required=True, help='an mvcoba-export folder with model.onnx')
  parser.add_argument('--actions', type=int, default=10)
  parser.add_argument('--seed', type=int, default=0)
  parser.add_argument('--failed-grasp-retries', type=int,
                      help="grasps again after this many failed grasps in a row before pushing, "
                           "in place of model.json's (a policy with failed_grasp_changes false)")
  parser.add_argument('--gripper', help="the robot's gripper (a preset of sim/grippers.py): "
                                         "refused unless it is the policy's")
  parser.add_argument('--other-gripper', action='store_true',
                      help='act with a gripper other than the one the policy trained with')
  args = parser.parse_args(argv)
  if args.actions < 1 or args.seed < 0:
    parser.error(f'--actions {args.actions} --seed {args.seed}: at least 1 action, a seed of 0 '
                 'or more')
  try:
    policy = OnnxPolicy(args.model, failed_grasp_retries=args.failed_grasp_retries,
                        gripper=args.gripper, other_gripper=args.other_gripper)
    rig = SimulatedRig(policy.spec.config, args.seed, args.gripper)
    run(rig, policy, calibration_from_dict(rig.calibration), args.actions)
  except DeployError as e:
    print(f'error: {e}', file=sys.stderr)
    return 2
  return 0


if __name__ == '__main__':
  sys.exit(main())
