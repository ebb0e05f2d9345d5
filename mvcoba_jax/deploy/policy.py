"""An exported policy (`mvcoba-export`'s folder) acting on heightmaps with onnxruntime (the graph
decides: network, rule and argmax), its input and action checked before a robot may take it, and
the change observation between two frames; numpy and onnxruntime only."""
from __future__ import annotations

import dataclasses
import math
import pathlib

import numpy as np

from mvcoba_jax.deploy import checks, model_file
from mvcoba_jax.deploy.calibration import Calibration, DeployError
from mvcoba_jax.sim.contract import (changed_views, filled, observed_change, pixel_to_world,
                                     push_length)


@dataclasses.dataclass(frozen=True)
class Action:
  """A primitive for the robot (m, rad), with the cell and score it came from: the one action
  record that leaves the project, in the robot's base frame from `OnnxPolicy.act` (given a
  calibration) and in the workspace frame from `Policy.act`."""
  primitive: str  # 'push' or 'grasp'
  position: tuple[float, float, float]  # the cell's centre at its surface height
  angle: float  # the gripper's yaw and the push direction about +z
  push_length: float  # m a push slides along `angle`: config.env.push_length, cut short at the
  # workspace's edge (`sim.contract.push_length`); 0 for a grasp
  opening: float  # m to open the fingers to before a grasp (the gripper's max_opening); 0 for
  # a push, which goes closed
  rotation: int
  row: int
  col: int
  q: float


def _flag(name: str, value, meaning: str) -> bool:
  """`value` as a bool when it is one (Python's or numpy's); DeployError otherwise: a robot's
  reading that is not a plain yes or no must not steer the rule by its truthiness."""
  if isinstance(value, (bool, np.bool_)):
    return bool(value)
  raise DeployError(f'{name}={value!r:.40}: True or False ({meaning})')


def _same(value, trained) -> bool:
  """Whether a gripper field given for the robot is the trained one's (numbers within 1e-6)."""
  try:
    return bool(np.allclose(np.asarray(value, float), np.asarray(trained, float), atol=1e-6))
  except (TypeError, ValueError):  # not numbers, or not as many
    return False


def check_gripper(trained: dict, robot: str | dict, folder) -> None:
  """DeployError unless the robot's gripper (a name, or the fields of one) is the one the policy
  trained with: same name, and where fields are given, the same values (1e-6 m)."""
  if not isinstance(robot, (str, dict)):
    raise DeployError(f'gripper={robot!r:.40}: a preset\'s name or a dict of its fields')
  name = robot if isinstance(robot, str) else robot.get('name')
  differs = [k for k, v in ({} if isinstance(robot, str) else robot).items()
             if k != 'name' and k in trained and not _same(v, trained[k])]
  if name != trained['name'] or differs:
    what = f'{name!r}' + (f' ({", ".join(f"{k} {robot[k]!r}" for k in differs)})'
                          if differs else '')
    raise DeployError(f'{folder}: the policy trained with gripper {trained["name"]!r} (opening '
                      f'{trained["max_opening"]:g} m), the robot has {what}; retrain for it '
                      '(docs/gripper.md), or act anyway with other_gripper=True '
                      '(--other-gripper)')


def check_graph(session, spec: model_file.ModelFile, onnx_file) -> None:
  """DeployError unless an onnxruntime session's graph reads and writes what model.json
  describes: inputs color (1, V, R, R, 3) and depth (1, V, R, R) float32 and changed (1,) bool,
  outputs action (1, 4) int32 and value (1,) float32, for its V views and R x R grid (a free
  dimension fits any size)."""
  v, r = spec.num_views, spec.grid_size
  needs = {'input': {'color': ('tensor(float)', [1, v, r, r, 3]),
                     'depth': ('tensor(float)', [1, v, r, r]), 'changed': ('tensor(bool)', [1])},
           'output': {'action': ('tensor(int32)', [1, 4]), 'value': ('tensor(float)', [1])}}
  for kind, has in (('input', session.get_inputs()), ('output', session.get_outputs())):
    named = {n.name: n for n in has}
    missing = sorted(set(needs[kind]) - set(named))
    extra = sorted(set(named) - set(needs[kind])) if kind == 'input' else []
    if missing or extra:
      more = ' and more' if kind == 'output' else ''  # an export may add outputs (q, score)
      raise DeployError(f'{onnx_file}: the graph\'s {kind}s are {", ".join(sorted(named))}; an '
                        f'export\'s are {", ".join(needs[kind])}{more}')
    for name, (dtype, shape) in needs[kind].items():
      got = list(named[name].shape)
      if named[name].type != dtype or len(got) != len(shape) or any(
          isinstance(g, int) and g != s for g, s in zip(got, shape)):
        raise DeployError(f'{onnx_file}: {kind} {name} is {named[name].type} {got}; model.json '
                          f'({v} views, a {r} x {r} grid) needs {dtype} {shape}')


class OnnxPolicy:
  """model.json and model.onnx of an export: the graph's greedy action on a state, given whether
  the last action changed the scene, as `examples/onnx_infer.py` runs it. `failed_grasp_changes`
  and `failed_grasp_retries`, when given, replace model.json's change rule after a failed grasp
  (`model_file.acting_rule`: what the rule does next, not what the network reads). `gripper`,
  the robot's (a preset's name, or its fields as `scene.gripper` holds them), is refused unless
  it is the one the policy trained with (`gripper` property), or `other_gripper` says to act
  anyway: grasps are learned for one pair of fingers."""

  def __init__(self, folder, failed_grasp_changes: bool | None = None,
               failed_grasp_retries: int | None = None, gripper: str | dict | None = None,
               other_gripper: bool = False):
    import onnxruntime as ort  # noqa: PLC0415 (only a policy needs it, not the heightmaps)
    self.folder = folder = pathlib.Path(folder)
    # refuses a damaged, unknown or hand-broken model.json, or a rule that cannot be
    self.spec = model_file.acting_rule(model_file.read(folder), failed_grasp_changes,
                                       failed_grasp_retries)
    if not self.spec.graph_decides:
      raise DeployError(f'{folder / "model.json"}: format {model_file.FORMATS[1]!r}: its graph '
                        'leaves the action rule to the runtime; export it again '
                        f'(mvcoba-export --checkpoint {folder} --out NEW_FOLDER)')
    if gripper is not None and not _flag('other_gripper', other_gripper,
                                         'act with a gripper other than the policy\'s'):
      check_gripper(self.gripper, gripper, folder)
    onnx_file = folder / self.spec.onnx_file
    options = ort.SessionOptions()
    options.log_severity_level = 3  # the converter's loose shape annotations only warn
    try:
      self.session = ort.InferenceSession(str(onnx_file), options,
                                          providers=['CPUExecutionProvider'])
    except Exception as e:  # noqa: BLE001 (onnxruntime raises its own kinds)
      raise DeployError(f'{onnx_file}: cannot load the network ({str(e)[:160]})') from None
    check_graph(self.session, self.spec, onnx_file)

  @property
  def gripper(self) -> dict:
    """The gripper the policy trained with, as model.json's config.scene.gripper holds it."""
    return self.spec.gripper

  def check(self, calibration: Calibration) -> None:
    """Refuses a calibration whose workspace grid or number of cameras is not the policy's."""
    if not isinstance(calibration, Calibration):
      raise DeployError(f'calibration={calibration!r:.40}: a deploy.Calibration expected '
                        '(deploy.load_calibration reads one from its file)')
    spec = self.spec
    if (abs(calibration.half - spec.workspace_half_m) > 1e-9
        or abs(calibration.resolution - spec.resolution_m) > 1e-9):
      raise DeployError(f'the calibration\'s workspace (half {calibration.half!r} m, resolution '
                        f'{calibration.resolution!r} m) is not the policy\'s (half '
                        f'{spec.workspace_half_m!r} m, resolution {spec.resolution_m!r} m)')
    if len(calibration.cameras) != spec.num_views:
      raise DeployError(f'the calibration has {len(calibration.cameras)} cameras, the policy reads '
                        f'{spec.num_views} views')

  def choose(self, color, depth, changed: bool) -> tuple[int, int, int, int, float]:
    """(primitive, rotation, row, col, score) of the graph's greedy action on heightmaps of every
    view."""
    action, value = self.session.run(['action', 'value'],
                                     {'color': np.asarray(color, np.float32)[None],
                                      'depth': np.asarray(depth, np.float32)[None],
                                      'changed': np.array([bool(changed)])})
    primitive, rotation, row, col = (int(i) for i in action[0])
    spec = self.spec
    if (primitive not in (spec.push, spec.grasp) or not 0 <= rotation < len(spec.angles_rad)
        or not (0 <= row < spec.grid_size and 0 <= col < spec.grid_size)):
      raise DeployError(f'refused: the graph chose primitive {primitive}, rotation {rotation}, '
                        f'cell ({row}, {col}): outside the policy\'s {len(spec.angles_rad)} '
                        f'rotations and {spec.grid_size} x {spec.grid_size} grid')
    return primitive, rotation, row, col, float(value[0])

  def act(self, color, depth, seen, changed: bool, calibration: Calibration) -> Action:
    """The greedy action in the robot's base frame, refused (DeployError, with the reason) from
    heightmaps of another grid or number of views than the policy's, heights not in metres or
    colour out of its range (`checks.observation`; non-finite cells count as unseen), a frame
    where a camera saw none of the workspace, or when the action has a non-finite score or would
    leave the workspace or go below the table (`checks.action`); a push ends at the workspace's
    edge at the farthest (`sim.contract.push_length`)."""
    changed = _flag('changed', changed, 'did the last action change the scene')
    self.check(calibration)
    spec = self.spec
    res, half = spec.resolution_m, spec.workspace_half_m
    try:
      color, depth = checks.observation(color, depth, spec.num_views, spec.grid_size,
                                        calibration.top)
      seen = checks.seen(seen, depth)
      checks.sighted(seen, spec.views_used, [c.name for c in calibration.cameras])
    except checks.Refused as e:
      raise DeployError(f'refused: {e}') from None
    if spec.fill_unseen:  # as training saw them: each view's unseen cells from the others
      color, depth = filled(color, depth, seen)
    used = list(spec.views_used)
    primitive, rotation, row, col, score = self.choose(color, depth, changed)
    x, y = pixel_to_world(row, col, res, half)
    z = float(depth[used, row, col].max())
    angle = spec.angles_rad[rotation] + calibration.yaw
    try:
      checks.action(score, angle, (x, y, z), half, calibration.top)
    except checks.Refused as e:
      raise DeployError(f'refused: {e}') from None
    grasp = primitive == spec.grasp
    push = 0.0 if grasp else float(push_length((x, y), spec.angles_rad[rotation],
                                                       spec.push_length_m, half))
    return Action(primitive='grasp' if grasp else 'push',
                  position=tuple(float(v) for v in calibration.workspace_to_base((x, y, z))),
                  angle=math.remainder(angle, 2 * math.pi), push_length=push,
                  opening=float(self.gripper['max_opening']) if grasp else 0.0,
                  rotation=rotation, row=row, col=col, q=score)

  def changed(self, before, after, grasped: bool | None = None, failures: int = 0) -> bool:
    """Whether the last action changed the scene, as the next action is chosen in training and
    evaluation (`sim.contract.observed_change`): between two frames' (depth, seen) heightmaps
    more cells than `change_area` / resolution^2 in some view changed height by between
    `change_min` and `change_max` (model.json's config; VPG's 300 cells at 2 mm, 1 to 30 cm),
    cells missing from either frame counting as unchanged, or a grasp held something (`grasped`
    True). A policy trained with `perception.failed_grasp_changes` off counts a grasp that held
    nothing (`grasped` False) as no change once `failures`, the failed actions in a row before it
    (`sim.contract.failures_after` counts them), reach its `failed_grasp_retries`. `grasped`:
    None after a push, or where the robot cannot tell (the frames decide)."""
    spec = self.spec
    if grasped is not None:
      grasped = _flag('grasped', grasped, 'did the grasp hold something; None after a push or '
                      'where the robot cannot tell')
    if isinstance(failures, (bool, np.bool_)) or not isinstance(
        failures, (int, np.integer)) or failures < 0:
      raise DeployError(f'failures={failures!r:.40}: a whole number of 0 or more (the failed '
                        'actions in a row before this one)')
    (d0, s0), (d1, s1) = (tuple(np.asarray(a) for a in frame) for frame in (before, after))
    if (not d0.shape == s0.shape == d1.shape == s1.shape or s0.dtype != np.bool_
        or s1.dtype != np.bool_):
      raise DeployError(f'changed: frames of depth {d0.shape} / {d1.shape} and seen {s0.shape} / '
                        f'{s1.shape}: two frames of one shape, seen as booleans')
    frames = changed_views(d0, s0, d1, s1, spec.change_min, spec.change_max, spec.change_area,
                           spec.resolution_m).any()
    _, rule = observed_change(frames, grasped is not None, bool(grasped), failures,
                              spec.failed_grasp_changes, spec.failed_grasp_retries)
    return bool(rule)
