"""From a lab's own RGB-D cameras to the heightmaps a trained policy acts on, with numpy and
OpenCV only (no JAX, no MuJoCo): a calibration file (`calibration.py`) and the projection that
training uses (`heightmaps.py`)."""
from mvcoba_jax.deploy.calibration import (Calibration, Camera, DeployError,
                                           calibration_from_dict, load_calibration)
from mvcoba_jax.deploy.heightmaps import heightmaps, read_depth

__all__ = ['Calibration', 'Camera', 'DeployError', 'calibration_from_dict', 'heightmaps',
           'load_calibration', 'read_depth']
