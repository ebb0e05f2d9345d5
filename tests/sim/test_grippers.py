"""Each gripper preset on each physics backend: the fingers open to the preset's opening, the
scripted grasp lifts a 5 cm cube, and a 10 cm flat box taken across its length is lifted by the
RG2 (11 cm) and not by the Robotiq 2F-85 (8.5 cm) or the Franka Hand (8 cm), which lift it across
its width."""
import jax
import numpy as np
import pytest

from mvcoba_jax.sim import grippers
from mvcoba_jax.sim.primitives import GRASP
from tests.helpers import BACKENDS, actions, layout, make_env, stack

CUBE, FLAT = 0, 2  # the tiny preset's slots: cube, cube, flat_box, flat_box
ACROSS_LENGTH, ACROSS_WIDTH = 4, 0  # rotations: fingers closing along x (the box's length), y
CASES = [((CUBE, 0.0, 0.0, 0.0), (GRASP, 0, 0.0, 0.0, 0.05)),
         ((FLAT, 0.0, 0.0, 0.0), (GRASP, ACROSS_LENGTH, 0.0, 0.0, 0.025)),
         ((FLAT, 0.0, 0.0, 0.0), (GRASP, ACROSS_WIDTH, 0.0, 0.0, 0.025))]


@pytest.fixture(scope='module', params=[(b, g) for g in grippers.PRESETS for b in BACKENDS],
                ids=lambda p: f'{p[1]}-{p[0]}')
def env(request):
  backend, gripper = request.param
  return make_env('tiny', backend, f'scene.gripper={gripper}')


def test_the_fingers_open_to_the_presets_opening(env):
  gripper = env.config.scene.gripper
  m = env.scene.mj_model
  left, right = (m.jnt_range[m.joint(name).id][1] for name in ('finger_left', 'finger_right'))
  assert abs(left + right - gripper.max_opening) < 1e-6
  finger = m.geom_size[m.geom('finger_left').id]
  np.testing.assert_allclose(2 * finger, (gripper.finger_width, gripper.finger_thickness,
                                          gripper.finger_length), atol=1e-6)


def test_grasps_lift_what_the_opening_takes(env):
  starts = stack([layout(env, [obj]) for obj, _ in CASES])
  start = jax.jit(jax.vmap(env.reset_from_case))(starts)
  _, info = jax.jit(jax.vmap(env.step))(start, actions([row for _, row in CASES]))
  cube, flat_long, flat_wide = np.asarray(info.grasp_success).tolist()
  assert cube and flat_wide, env.config.scene.gripper.name
  assert flat_long == (env.config.scene.gripper.max_opening > 0.1), env.config.scene.gripper.name
  assert np.asarray(info.healthy).all()
