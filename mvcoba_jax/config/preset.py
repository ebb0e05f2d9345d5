"""Presets: a module of `mvcoba_jax.presets` named by `--config`, or a Python file given by path;
either defines `get_config() -> Config`. `resolve` is a preset with `--set` overrides applied."""
from __future__ import annotations

import importlib
import importlib.util
import pathlib
import typing

from mvcoba_jax.config.overrides import override
from mvcoba_jax.config.schema import Config, ConfigError
from mvcoba_jax.config.validation import validate


# The modules of mvcoba_jax.presets.
PRESETS = ('default', 'objects', 'reproduction', 'paper', 'paper_text', 'authors', 'gpu', 'tiny')


def load_preset(preset: str | pathlib.Path) -> Config:
  """Config returned by `get_config()` of a preset named in `PRESETS` or of a preset file."""
  if str(preset) in PRESETS:
    module = importlib.import_module(f'mvcoba_jax.presets.{preset}')
  else:
    path = pathlib.Path(preset)
    if not path.is_file():
      raise ConfigError(f'config preset {path}: neither a file nor one of {", ".join(PRESETS)}')
    if path.suffix != '.py':
      raise ConfigError(f'config preset {path}: a preset file is Python (.py) that defines '
                        'get_config()')
    spec = importlib.util.spec_from_file_location(f'mvcoba_preset_{path.stem}', path)
    module = importlib.util.module_from_spec(spec)
    try:
      spec.loader.exec_module(module)
    except (Exception, SystemExit) as e:  # a user's Python file: its error is theirs, named
      raise ConfigError(f'config preset {path}: {type(e).__name__}: {str(e)[:200]}') from None
  if not hasattr(module, 'get_config'):
    raise ConfigError(f'config preset {preset} defines no get_config()')
  try:
    config = module.get_config()
  except ConfigError:
    raise
  except (Exception, SystemExit) as e:  # a user's Python: its error is theirs, named
    raise ConfigError(f'config preset {preset}: get_config() raised {type(e).__name__}: '
                      f'{str(e)[:200]}') from None
  if not isinstance(config, Config):
    raise ConfigError(f'config preset {preset}: get_config() returned {type(config).__name__}, '
                      'not a mvcoba_jax.config.Config')
  return config


def resolve(preset: str | pathlib.Path | None, overrides: typing.Sequence[str] = ()) -> Config:
  """The preset (or the default preset) with `overrides` applied in order."""
  if preset is None:
    preset = 'default'
  config = load_preset(preset)
  for assignment in overrides:
    config = override(config, assignment)
  return validate(config)


def add_arguments(parser) -> None:
  """The `--config` and `--set` options every entry point takes."""
  parser.add_argument('--config', default=None,
                      help=f'preset: {"/".join(PRESETS)} or a preset file (default: default)')
  parser.add_argument('--set', dest='overrides', action='append', default=[],
                      metavar='KEY=VALUE', help='override a config field, e.g. env.num_objects=5')


def from_arguments(args) -> Config:
  return resolve(args.config, args.overrides)
