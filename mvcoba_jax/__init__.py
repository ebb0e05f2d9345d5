"""mvcoba-jax: batched MuJoCo push-and-grasp learning in clutter and occlusion (MV-COBA).

`mvcoba_jax.train`, `sweep`, `evaluate`, `join_evaluations` and `load_policy` are the library
calls under the commands, with every other name of `mvcoba_jax/api.py`'s `__all__` (`Policy`,
`EvalSpec`, the errors), and `reproduce` is mvcoba-reproduce's (`mvcoba_jax/reproduction.py`);
they are imported on first use, so importing the package stays light.
"""
__version__ = '0.1.0'


def __getattr__(name: str):
  if name.startswith('__'):  # tools probing dunders must not import JAX
    raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
  import importlib  # noqa: PLC0415
  api = importlib.import_module('mvcoba_jax.api')  # not `from mvcoba_jax import`: that asks here
  if name in api.__all__:
    return getattr(api, name)
  if name == 'reproduce':
    from mvcoba_jax.reproduction import reproduce  # noqa: PLC0415
    return reproduce
  raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
