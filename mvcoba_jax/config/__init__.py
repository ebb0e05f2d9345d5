"""Configuration: frozen dataclasses (`schema.py`), checked together (`validation.py`), made from
presets (`preset.py`) with `key=value` overrides (`overrides.py`), saved and read back
(`saved.py`). Everything is imported from here: `from mvcoba_jax.config import Config, resolve`.
"""
from mvcoba_jax.config.overrides import (ACTING_RULE, FIXED_BY_TRAINING, evaluated,
                                         override)
from mvcoba_jax.config.preset import (PRESETS, add_arguments, from_arguments, load_preset,
                                      resolve)
from mvcoba_jax.config.saved import (LEGACY, RETIRED, RUNTIME_FIELDS, defaulted, flat, from_dict,
                                     to_dict, trained_as)
from mvcoba_jax.config.schema import (ACTIVATION_LIMIT_BYTES, DENSENET_GROWTH, FUTURE_MAX,
                                      MAX_ACTIONS_LIMIT, PHASE_LIMIT_S, REPLAY_LIMIT_BYTES,
                                      TARGETS, TRUNKS, Between, CameraConfig, Config,
                                      ConfigError, EnvConfig, Error, GripperConfig,
                                      NetworkConfig,
                                      PerceptionConfig, SceneConfig, TabletopConfig,
                                      TrainConfig, check)
from mvcoba_jax.config.validation import validate

__all__ = ['ACTING_RULE', 'ACTIVATION_LIMIT_BYTES', 'Between', 'CameraConfig', 'Config',
           'ConfigError', 'DENSENET_GROWTH', 'EnvConfig', 'Error', 'FIXED_BY_TRAINING',
           'GripperConfig',
           'FUTURE_MAX', 'LEGACY', 'MAX_ACTIONS_LIMIT', 'NetworkConfig', 'PHASE_LIMIT_S', 'PRESETS',
           'PerceptionConfig', 'REPLAY_LIMIT_BYTES', 'RETIRED', 'RUNTIME_FIELDS', 'SceneConfig',
           'TARGETS', 'TRUNKS', 'TabletopConfig', 'TrainConfig', 'add_arguments', 'check',
           'defaulted', 'evaluated', 'flat', 'from_arguments', 'from_dict', 'load_preset',
           'override', 'resolve', 'to_dict', 'trained_as', 'validate']
