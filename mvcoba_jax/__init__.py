"""mvcoba-jax: batched MuJoCo push-and-grasp learning in clutter and occlusion (MV-COBA).

`mvcoba_jax.train`, `sweep`, `evaluate`, `join_evaluations` and `load_policy` are the library
calls under the commands (`mvcoba_jax/api.py`), and `reproduce` is mvcoba-reproduce's
(`mvcoba_jax/reproduction.py`); they are imported on first use, so importing the package stays
light.
"""
__version__ = '0.1.0'


def __getattr__(name: str):
  if name in ('train', 'sweep', 'evaluate', 'join_evaluations', 'load_policy', 'TrainResult',
              'TrainError', 'EvaluationError', 'Error'):
    from mvcoba_jax import api  # noqa: PLC0415
    return getattr(api, name)
  if name == 'reproduce':
    from mvcoba_jax.reproduction import reproduce  # noqa: PLC0415
    return reproduce
  raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
