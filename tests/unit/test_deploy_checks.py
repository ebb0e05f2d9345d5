"""The checks around a policy's network (deploy/checks.py): what may reach it, what may leave it."""
import math

import numpy as np
import pytest

from mvcoba_jax.deploy import checks

SIDE, TOP, HALF = 8, 0.4, 0.224


def obs(views=2, depth=0.05, color=0.5):
  return (np.full((views, SIDE, SIDE, 3), color, np.float32),
          np.full((views, SIDE, SIDE), depth, np.float32))


def test_a_sound_observation_passes_scaled_and_with_unseen_cells_zeroed():
  color, depth = obs()
  depth[0, 0, 0], color[1, 2, 2, 1] = np.nan, np.inf
  c, d = checks.observation(color, depth, 2, SIDE, TOP)
  assert d[0, 0, 0] == 0.0 and c[1, 2, 2, 1] == 0.0 and d.dtype == c.dtype == np.float32
  c8, _ = checks.observation(np.full((2, SIDE, SIDE, 3), 255, np.uint8), obs()[1], 2, SIDE, TOP)
  c16, _ = checks.observation(np.full((2, SIDE, SIDE, 3), 65535, np.uint16), obs()[1], 2, SIDE,
                              TOP)
  assert c8.max() == c16.max() == 1.0
  _, d = checks.observation(*obs(depth=-0.004), 2, SIDE, TOP)
  assert d.min() == 0.0  # a few mm below the table is the table


@pytest.mark.parametrize('what, color, depth, match', [
    ('millimetres', *obs(depth=50.0), 'millimetres'),
    ('below the table', *obs(depth=-0.02), 'below'),
    ('one view', *obs(views=1), r'the policy takes \(2, 8, 8\)'),
    ('colour 0-255 floats', *obs(color=200.0), '0..1'),
    ('negative colour', *obs(color=-0.5), '0..1'),
    ('blind camera', obs()[0], np.full((2, SIDE, SIDE), np.nan), 'view 0: its depth'),
    ('blind colour', np.full((2, SIDE, SIDE, 3), np.nan), obs()[1], 'view 0: its colour'),
    ('int32 colour', obs()[0].astype(np.int32), obs()[1], 'dtype int32'),
    ('object depth', obs()[0], np.array([None] * 4), 'dtype object'),
])
def test_a_broken_observation_is_refused_in_one_line(what, color, depth, match):
  with pytest.raises(checks.Refused, match=match) as e:
    checks.observation(color, depth, 2, SIDE, TOP)
  assert '\n' not in str(e.value), what


@pytest.mark.parametrize('q, angle, position, match', [
    (math.nan, 0.0, (0.0, 0.0, 0.05), 'non-finite'),
    (math.inf, 0.0, (0.0, 0.0, 0.05), 'non-finite'),
    (1.0, math.nan, (0.0, 0.0, 0.05), 'angle'),
    (1.0, 0.0, (0.3, 0.0, 0.05), 'leaves the workspace'),
    (1.0, 0.0, (0.0, -0.3, 0.05), 'leaves the workspace'),
    (1.0, 0.0, (0.0, 0.0, -0.01), 'leaves the workspace'),
    (1.0, 0.0, (0.0, 0.0, 30.0), 'leaves the workspace'),
    (1.0, 0.0, (0.0, math.nan, 0.05), 'leaves the workspace'),
])
def test_an_unsafe_action_is_refused(q, angle, position, match):
  with pytest.raises(checks.Refused, match=match):
    checks.action(q, angle, position, HALF, TOP)
  checks.action(1.0, 0.5, (0.2, -0.2, 0.1), HALF, TOP)  # a sound one passes
