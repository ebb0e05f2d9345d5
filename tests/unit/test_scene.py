"""The compiled MuJoCo model carries the scene config's contact settings (no physics)."""
import dataclasses

import mujoco
import numpy as np
import pytest

from mvcoba_jax.config import ConfigError, SceneConfig
from mvcoba_jax.sim.scene import build_mjcf


def test_every_geom_gets_the_configured_contact_time_constant():
  scene = dataclasses.replace(SceneConfig(), contact_timeconst=0.011)
  model = mujoco.MjModel.from_xml_string(build_mjcf(scene))
  np.testing.assert_allclose(model.geom_solref, np.tile([0.011, 1.0], (model.ngeom, 1)))


def test_time_constant_below_two_timesteps_is_refused():
  """MuJoCo would silently raise it to 2 timesteps: the config refuses it when built."""
  with pytest.raises(ConfigError, match='contact_timeconst=0.005 is below 2 x scene.timestep'):
    dataclasses.replace(SceneConfig(), timestep=0.004, contact_timeconst=0.005)
