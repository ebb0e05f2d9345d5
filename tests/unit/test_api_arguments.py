"""Every public library call refuses every argument of the wrong type or out of its range with
one `mvcoba_jax.Error` line naming the argument, before any folder is made or anything compiles
(bad values generated per kind of argument, one bad argument a call, in a fixed order)."""
import inspect
import pathlib
import random

import pytest

import mvcoba_jax

BAD = {
    'path': [3, None, [], b'runs', '', 2.5],
    'paths': [3, None, [3], [None], b'x', {'a': 1}],
    'flag': ['yes', 1, None, 0.0, []],
    'count': [2.5, '3', None, True, [1], float('nan')],
    'names': [3, None, [3], [''], [None], {'random'}],
    'config': [3, None, {}, ['tiny'], 'no-such-preset'],
    'choice': ['nosuch', 3, None, ['frozen']],
    'seeds': [[0, 0], '0', [2 ** 40], [-1], [0.5], []],
}


def calls(tmp: pathlib.Path):
  """(function, the good arguments, {argument: kind}) of every public call."""
  out = tmp / 'out'
  return [
      (mvcoba_jax.train, {'config': 'tiny', 'workdir': tmp / 'run', 'eval_actions': 4},
       {'config': 'config', 'workdir': 'path', 'resume': 'flag', 'overwrite': 'flag',
        'eval_actions': 'count', 'progress': 'flag'}),
      (mvcoba_jax.sweep, {'config': 'tiny', 'workdir': tmp / 'sweep', 'seeds': [0]},
       {'config': 'config', 'workdir': 'path', 'methods': 'names', 'seeds': 'seeds',
        'resume': 'flag', 'overwrite': 'flag', 'eval_actions': 'count', 'progress': 'flag'}),
      (mvcoba_jax.evaluate, {'baseline': 'heuristic', 'suites': ['isolated'], 'config': 'tiny',
                             'out': out},
       {'checkpoints': 'paths', 'suites': 'names', 'baseline': 'choice', 'runs': 'count',
        'max_actions': 'count', 'seed': 'count', 'protocol': 'choice', 'overrides': 'names',
        'out': 'path', 'resume': 'flag', 'overwrite': 'flag', 'video': 'flag',
        'progress': 'flag'}),
      (mvcoba_jax.join_evaluations, {'evaluations': [tmp / 'e'], 'out': out},
       {'evaluations': 'paths', 'out': 'path', 'overwrite': 'flag'}),
      (mvcoba_jax.load_policy, {'workdir': tmp / 'run'}, {'workdir': 'path'}),
      (mvcoba_jax.reproduce, {'config': 'tiny', 'workdir': tmp / 'rep', 'out': out},
       {'config': 'config', 'methods': 'names', 'seeds': 'seeds', 'actions': 'count',
        'runs': 'count', 'max_actions': 'count', 'suites': 'names', 'protocols': 'names',
        'workdir': 'path', 'out': 'path', 'progress': 'flag'}),
  ]


def bad_calls(tmp):
  """Every call with one argument bad, but for a value that is the argument's default (None:
  the method of the config, no baseline; no checkpoints)."""
  found = []
  for fn, good, kinds in calls(tmp):
    defaults = {n: p.default for n, p in inspect.signature(fn).parameters.items()}
    for name, kind in kinds.items():
      found += [(fn, good, name, value) for value in BAD[kind]
                if not (value is None and defaults.get(name) is None)
                and not (name == 'checkpoints' and value == [])]
  random.Random(0).shuffle(found)
  return found


def test_every_bad_argument_is_one_line_naming_it(tmp_path):
  tried = 0
  for fn, good, name, value in bad_calls(tmp_path):
    arguments = dict(good) | {name: value}
    args = [arguments.pop(k) for k in ('config', 'workdir') if k in arguments
            and fn in (mvcoba_jax.train, mvcoba_jax.sweep)]
    if fn is mvcoba_jax.load_policy:
      args = [arguments.pop('workdir')]
    if fn is mvcoba_jax.join_evaluations:
      args = [arguments.pop('evaluations'), arguments.pop('out')]
    if fn is mvcoba_jax.reproduce:
      args = [arguments.pop('config')]
    try:
      fn(*args, **arguments)
    except mvcoba_jax.Error as e:
      message = str(e)
    else:
      pytest.fail(f'{fn.__name__}({name}={value!r}) was accepted')
    shown = 'config preset' if value == 'no-such-preset' else name
    assert '\n' not in message and shown in message, (fn.__name__, name, value, message)
    tried += 1
  assert tried > 200
  assert sorted(p.name for p in tmp_path.iterdir()) == []  # nothing made


def test_every_name_of_the_api_is_reachable_from_the_package():
  """`mvcoba_jax.X` for every name of api.__all__ (Policy among them) and `reproduce`."""
  import mvcoba_jax
  from mvcoba_jax import api
  assert 'Policy' in api.__all__ and sorted(mvcoba_jax.API) == sorted(api.__all__)
  for name in [*api.__all__, 'reproduce']:
    assert getattr(mvcoba_jax, name) is not None, name


def test_numpy_numbers_are_taken_and_a_recipes_string_refused():
  """Counts and numbers from numpy arrays (np.int64, np.float32) are taken as Python's; bools
  are not counts; `reproduce(recipes=...)` takes a dict of method -> preset, in one line."""
  import numpy as np

  from mvcoba_jax import arguments
  from mvcoba_jax.reproduction import trained_for
  assert arguments.count('c', 'n', np.int64(3), 0, 5) == 3
  assert arguments.counts('c', 'n', np.int32(2), 0, 5) == [2]
  assert arguments.number('c', 'n', np.float32(0.5), 0, 1) == 0.5
  for bad in (True, np.bool_(True), 1.5):
    with pytest.raises(arguments.ArgumentError, match='expected a whole number'):
      arguments.count('c', 'n', bad, 0, 5)
  with pytest.raises(arguments.ArgumentError, match="recipes='default': expected a dict"):
    trained_for('mvcoba_jax.reproduce', 'tiny', 'default', ['mvcoba'], 8)
  with pytest.raises(arguments.ArgumentError, match="recipes names 'mvcobaa', not a method"):
    trained_for('mvcoba_jax.reproduce', 'tiny', {'mvcobaa': 'tiny'}, ['mvcoba'], 8)
  chosen = trained_for('c', 'tiny', {'mvcoba': 'tiny'}, ['mvcoba'], 8)
  assert chosen['mvcoba'].train.total_actions == 8
