"""mvcoba-jax: batched MuJoCo push-and-grasp learning in clutter and occlusion (MV-COBA).

`mvcoba_jax.train`, `sweep`, `evaluate`, `join_evaluations` and `load_policy` are the library
calls under the commands, with every other name of `mvcoba_jax/api.py`'s `__all__` (`Policy`,
`EvalSpec`, the errors), and `reproduce` is mvcoba-reproduce's (`mvcoba_jax/reproduction.py`);
they are imported on first use, so importing the package stays light.
"""
__version__ = '0.1.0'


# The names of api.__all__ (tests/unit/test_api_arguments.py holds the two lists together): a
# fixed list, so that `from mvcoba_jax import methods` and the like, which ask here before they
# import the submodule, are not answered by importing the API halfway through.
API = ('Error', 'EvalSpec', 'EvaluationError', 'Policy', 'RESULT_FILES', 'RUN_FILES',
       'TrainError', 'TrainResult', 'check_work', 'evaluate', 'join_evaluations', 'load_policy',
       'resumable', 'sweep', 'sweep_runs', 'train')


def __getattr__(name: str):
  if name in API:
    from mvcoba_jax import api  # noqa: PLC0415
    return getattr(api, name)
  if name == 'reproduce':
    from mvcoba_jax.reproduction import reproduce  # noqa: PLC0415
    return reproduce
  raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
