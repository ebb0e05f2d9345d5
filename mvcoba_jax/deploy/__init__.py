"""From a lab's own RGB-D cameras to a checked action in its robot's base frame, with numpy,
OpenCV and onnxruntime only (no JAX, no MuJoCo): a calibration file (`calibration.py`), the
projection that training uses (`heightmaps.py`) and an exported policy acting on it
(`policy.py`)."""
from mvcoba_jax.deploy.calibration import (Calibration, Camera, DeployError,
                                           calibration_from_dict, load_calibration)
from mvcoba_jax.deploy.heightmaps import heightmaps, read_color, read_depth
from mvcoba_jax.deploy.policy import Action, OnnxPolicy

__all__ = ['Action', 'Calibration', 'Camera', 'DeployError', 'OnnxPolicy', 'calibration_from_dict',
           'heightmaps', 'load_calibration', 'read_color', 'read_depth']
