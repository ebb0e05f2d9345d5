"""The library calls' arguments, checked where they come in: a wrong type or value ends in one
line that names the call and the argument (`ArgumentError`, an `Error`), before any folder is
claimed or anything compiles. Each helper returns the value in the form the call uses."""
from __future__ import annotations

import math
import numbers
import os
import pathlib

from mvcoba_jax import config as config_lib
from mvcoba_jax.config import Config, Error


class ArgumentError(Error):
  """An argument of a library call of the wrong type or out of its range."""


def _show(value) -> str:
  return repr(value)[:60]


def config(call: str, value) -> Config:
  """A Config, or the name of a preset or preset file (`config.resolve`)."""
  if isinstance(value, Config):
    return value
  if isinstance(value, (str, os.PathLike)):
    return config_lib.resolve(str(value))
  raise ArgumentError(f'{call}: config={_show(value)}: expected a Config or a preset name '
                      f'({", ".join(config_lib.PRESETS)}) or file')


def path(call: str, name: str, value) -> pathlib.Path:
  if isinstance(value, (str, os.PathLike)) and str(value):
    return pathlib.Path(value)
  raise ArgumentError(f'{call}: {name}={_show(value)}: expected a path')


def paths(call: str, name: str, value, at_least: int = 1) -> list[pathlib.Path]:
  """A list of paths; a lone path is a list of one."""
  items = [value] if isinstance(value, (str, os.PathLike)) else value
  if not isinstance(items, (list, tuple)) or len(items) < at_least:
    raise ArgumentError(f'{call}: {name}={_show(value)}: expected a list of at least {at_least} '
                        'paths')
  return [path(call, name, v) for v in items]


def names(call: str, name: str, value, allowed=None, at_least: int = 1,
          distinct: bool = True) -> list[str]:
  """A list of strings (of `allowed` when given; paths are taken as their strings), without
  repeats when `distinct`; a lone string is a list of one."""
  items = [value] if isinstance(value, (str, os.PathLike)) else value
  if isinstance(items, (list, tuple)):
    items = [str(v) if isinstance(v, os.PathLike) else v for v in items]
  if (not isinstance(items, (list, tuple)) or len(items) < at_least
      or not all(isinstance(v, str) and v for v in items)):
    raise ArgumentError(f'{call}: {name}={_show(value)}: expected a list of at least {at_least} '
                        'names')
  unknown = [v for v in items if allowed is not None and v not in allowed]
  if unknown or (distinct and len(set(items)) < len(items)):
    raise ArgumentError(f'{call}: {name}={_show(value)}: '
                        + (f'{unknown[0]!r} is not one of {", ".join(allowed)}' if unknown
                           else 'a name is given twice'))
  return list(items)


def choice(call: str, name: str, value, allowed) -> str:
  if isinstance(value, str) and value in allowed:
    return value
  raise ArgumentError(f'{call}: {name}={_show(value)}: one of {", ".join(map(str, allowed))}')


def flag(call: str, name: str, value) -> bool:
  if isinstance(value, bool):
    return value
  raise ArgumentError(f'{call}: {name}={_show(value)}: expected True or False')


def _whole(value) -> bool:
  """A whole number of Python or numpy (np.int64 from an array), not a bool (numpy's bool is no
  `numbers.Integral`)."""
  return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def count(call: str, name: str, value, low: int, high: int) -> int:
  if _whole(value) and low <= value <= high:
    return int(value)
  raise ArgumentError(f'{call}: {name}={_show(value)}: expected a whole number in [{low}, '
                      f'{high}]')


def counts(call: str, name: str, value, low: int, high: int) -> list[int]:
  """A list of distinct whole numbers; a lone number is a list of one."""
  items = [value] if _whole(value) else value
  if not isinstance(items, (list, tuple)) or not items:
    raise ArgumentError(f'{call}: {name}={_show(value)}: expected a list of whole numbers')
  items = [count(call, name, v, low, high) for v in items]
  if len(set(items)) < len(items):
    raise ArgumentError(f'{call}: {name}={_show(value)}: a number is given twice')
  return items


def number(call: str, name: str, value, low: float, high: float) -> float:
  if (isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)
      and low <= value <= high):
    return float(value)
  raise ArgumentError(f'{call}: {name}={_show(value)}: expected a number in [{low:g}, {high:g}]')
