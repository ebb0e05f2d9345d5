"""Exports a trained Q-network for use outside JAX (SPEC section 8).

  python -m mvcoba_jax.export --checkpoint WORKDIR --out DIR

WORKDIR is a `train.py` work directory (config.json, checkpoints/). DIR gets the following; `load`
reads it back (eval.py --checkpoint DIR), so a trained policy travels without its training state:
- params.npz: the network parameters by flat name (`fcns/0/trunk/blocks/0/conv1/kernel`);
- model.onnx: the Q-network forward for one state and all K rotations, rotations included;
- model.json: names, shapes and dtypes of the parameters, the config, the heightmap frame, the
  rotations, the input normalisation, the method's action rule and what the ONNX graph leaves
  to the caller (the action rule and pixel -> world), all that `examples/onnx_infer.py` needs.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import pathlib
import sys
import warnings
from unittest import mock

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx

from envs.primitives import GRASP, PUSH
from mvcoba_jax import methods, networks, perception
from mvcoba_jax import config as config_lib
from mvcoba_jax.checkpoint import CheckpointError, Checkpoints, incompatibilities
from mvcoba_jax.config import Config
from mvcoba_jax.geometry import rotation_angle
from mvcoba_jax.training import Trainer

ONNX_OPSET = 23
FORMAT = 'mvcoba-jax-export/1'


class ExportError(RuntimeError):
  """A work directory that cannot be exported; the message names the path or config keys."""


def _config(saved: dict, path: pathlib.Path) -> Config:
  """The config of a saved run's JSON; warns about fields it lacks, which take today's defaults."""
  config = config_lib.from_dict(saved, where=str(path))
  defaulted = config_lib.defaulted(saved, config)
  if defaulted:  # e.g. a run from before scene.contact_timeconst trained with other physics
    warnings.warn(f'{path} lacks fields added since it was written; they take the current '
                  f'defaults: {", ".join(f"{k}={v!r}" for k, v in defaulted.items())} '
                  '(add them to it if its run used other values)', stacklevel=3)
  return config


def load(workdir) -> tuple[Config, networks.QNetwork, int]:
  """(config, Q-network, step) of the latest checkpoint in a `train.py` work directory, or of
  a folder that `export` wrote (model.json, params.npz: see `load_exported`).

  For a work directory the config (config.json) is checked against the checkpoint's before the
  scene is built, then the whole training state is restored through `Checkpoints.restore`,
  the path of `train.py --resume`; its structure comes from `jax.eval_shape`, which traces but
  compiles nothing.
  """
  workdir = pathlib.Path(workdir)
  if (workdir / 'model.json').is_file():
    return load_exported(workdir)
  config_path = workdir / 'config.json'
  if not config_path.is_file():
    raise ExportError(f'{config_path} does not exist: --checkpoint takes the work directory of '
                      'a train.py run (config.json, checkpoints/) or a folder written by '
                      'mvcoba_jax.export (model.json, params.npz)')
  if not (workdir / 'checkpoints').is_dir():  # Checkpoints() would create it
    raise ExportError(f'no checkpoints in {workdir / "checkpoints"}')
  try:
    config = _config(json.loads(config_path.read_text()), config_path)
  except (ValueError, TypeError) as e:  # bad JSON or values that do not fit the fields
    raise ExportError(f'{config_path}: {e}') from None
  checkpoints = Checkpoints(workdir)
  step = checkpoints.latest()
  if step is None:
    raise ExportError(f'no checkpoint in {checkpoints.directory}')
  where = checkpoints.directory / str(step)
  problems = incompatibilities(checkpoints.meta(step)['config'], config_lib.to_dict(config))
  if problems:
    raise ExportError(f'{config_path} does not match checkpoint {where}:\n  '
                      + '\n  '.join(problems))
  try:
    trainer = Trainer(config)
  except ValueError as e:  # an unknown method or trunk
    raise ExportError(f'{config_path}: {e}') from None
  like = jax.eval_shape(trainer.init, jax.random.PRNGKey(config.seed))
  try:
    state, _ = checkpoints.restore(like, config, step)
  except (CheckpointError, ValueError, KeyError) as e:  # the network code changed since
    raise ExportError(f'checkpoint {where} does not fit the network of {config_path}: {e}'
                      ) from None
  return config, nnx.merge(trainer.graphdef, state.params), step


def flat_params(model: networks.QNetwork) -> dict[str, np.ndarray]:
  """`fcns/0/trunk/blocks/0/conv1/kernel` -> array: the NNX state path joined by '/'."""
  out = {}

  def walk(tree, prefix):
    for k, v in tree.items():
      if isinstance(v, dict):
        walk(v, f'{prefix}{k}/')
      else:
        out[f'{prefix}{k}'] = np.asarray(v)

  walk(nnx.to_pure_dict(nnx.state(model)), '')
  return out


def load_exported(folder) -> tuple[Config, networks.QNetwork, int]:
  """(config, Q-network, step) from what `export` wrote: a trained policy without its training
  state (replay, optimiser), small enough to ship, as `pretrained/` does.

  Every parameter must be in params.npz with the shape the network of model.json's config
  expects; otherwise the error names the arrays that differ.
  """
  folder = pathlib.Path(folder)
  model_path, params_path = folder / 'model.json', folder / 'params.npz'
  try:
    described = json.loads(model_path.read_text())
    if described.get('format') != FORMAT:
      raise ValueError(f'format {described.get("format")!r}, expected {FORMAT!r}')
    config = _config(described['config'], model_path)
    step = int(described['source']['checkpoint_step'])
    model = networks.build_network(config.network, config.env.num_rotations, nnx.Rngs(0))
  except (OSError, ValueError, TypeError, KeyError, AttributeError) as e:
    raise ExportError(f'{model_path}: not an export of mvcoba_jax ({e})') from None
  want = {n: a.shape for n, a in flat_params(model).items()}
  try:
    with np.load(params_path) as saved:
      got = {n: saved[n] for n in saved.files}
  except (OSError, ValueError) as e:
    raise ExportError(f'{params_path}: cannot read it ({e})') from None
  problems = ([f'{n}: missing' for n in sorted(set(want) - set(got))]
              + [f'{n}: not a parameter of this network' for n in sorted(set(got) - set(want))]
              + [f'{n}: shape {got[n].shape}, the network needs {want[n]}'
                 for n in sorted(set(want) & set(got)) if got[n].shape != want[n]])
  if problems:
    raise ExportError(f'{params_path} does not fit the {config.network.method} network of '
                      f'{model_path}:\n  ' + '\n  '.join(problems[:10]))

  def filled(tree, prefix):
    return {k: filled(v, f'{prefix}{k}/') if isinstance(v, dict)
            else jnp.asarray(got[f'{prefix}{k}']) for k, v in tree.items()}

  state = nnx.state(model)
  nnx.replace_by_pure_dict(state, filled(nnx.to_pure_dict(state), ''))
  nnx.update(model, state)
  return config, model, step


def _enlarge_without_antialias():
  """jax.image.resize antialiases by default, which does nothing when enlarging (the network's
  only resize) but which jax2onnx refuses; this states the identical antialias=False instead.

  Installed while jax2onnx traces, on top of its own patch of jax.image.resize.
  """
  resize = jax.image.resize

  def enlarge(image, shape, method, antialias=True, precision=None):
    if any(o < i for o, i in zip(shape, image.shape)):
      raise ExportError(f'the network shrinks {image.shape} to {shape}; the ONNX export assumes '
                        'resizes only enlarge')
    return resize(image, shape, method, antialias=False, precision=precision)

  return mock.patch.object(jax.image, 'resize', enlarge)


def onnx_model(config: Config, model: networks.QNetwork):
  """ModelProto of (color (1, V, R, R, 3), depth (1, V, R, R)) -> q (1, 2, K, R, R)."""
  # jax2onnx's plugins for dm_pix, which the network does not use, fail to import under this
  # JAX and log a traceback each; they are skipped either way.
  logging.getLogger('jax2onnx.plugins.plugin_system').setLevel(logging.ERROR)
  try:
    from jax2onnx import to_onnx  # a dev extra: the rest of this module works without it
  except ImportError as e:
    raise ExportError(f'model.onnx needs jax2onnx ({e}); pip install -e ".[dev]"') from None

  graphdef, params = nnx.split(model)
  side, views = perception.grid_size(config), len(config.scene.cameras)

  def forward(color, depth):
    with _enlarge_without_antialias():
      return nnx.merge(graphdef, params)(color, depth)

  return to_onnx(forward, [jax.ShapeDtypeStruct((1, views, side, side, 3), jnp.float32),
                           jax.ShapeDtypeStruct((1, views, side, side), jnp.float32)],
                 model_name=f'mvcoba_{config.network.method}_q', opset=ONNX_OPSET,
                 input_names=['color', 'depth'], output_names=['q'])


def action_rule(method: str) -> dict:
  """The primitive choice of `agent.rule_primitive`, in words and as a name the example reads."""
  name = methods.get(method).rule
  text = methods.RULES[name]
  return {'name': name, 'primitive': text,
          'pixel': ('argmax of that primitive\'s Q over (rotation, row, col), flattened in that '
                    'order; the first maximum wins'),
          'greedy': 'exploration (epsilon-greedy) is a training matter and is not exported'}


def describe(config: Config, params: dict[str, np.ndarray], step: int, workdir) -> dict:
  """The content of model.json."""
  side, k = perception.grid_size(config), config.env.num_rotations
  views, num_views = networks.views_used(config.network.method), len(config.scene.cameras)
  res, half = config.perception.heightmap_resolution, config.scene.workspace_half
  return {
      'format': FORMAT,
      'source': {'workdir': str(pathlib.Path(workdir).resolve()), 'checkpoint_step': step},
      'method': config.network.method,
      'network': dataclasses.asdict(config.network),
      'config': config_lib.to_dict(config),
      'params': {'file': 'params.npz',
                 'arrays': {n: {'shape': list(a.shape), 'dtype': str(a.dtype)}
                            for n, a in params.items()},
                 'naming': 'the Flax NNX state path joined by "/" (list indices as numbers)'},
      'primitives': {'push': PUSH, 'grasp': GRASP},
      'no_action': networks.NO_ACTION,
      'action_rule': action_rule(config.network.method),
      'rotations': {'num_rotations': k,
                    'angles_rad': rotation_angle(np.arange(k), k).tolist(),
                    'formula': 'angle(k) = k * 2 * pi / num_rotations',
                    'meaning': ('rotation index k: the yaw of the gripper and the push '
                                'direction, counter-clockwise from +x (col) towards +y (row)')},
      'heightmap': {'resolution_m': res, 'grid_size': side, 'workspace_half_m': half,
                    'workspace_bounds_m': {'x': [-half, half], 'y': [-half, half]},
                    'num_views': num_views, 'views_used': list(views)},
      'pixel_to_world': {'x': 'x = -workspace_half_m + (col + 0.5) * resolution_m',
                         'y': 'y = -workspace_half_m + (row + 0.5) * resolution_m',
                         'z': 'z = max over views_used of depth[view, row, col]',
                         'meaning': 'the centre of cell (row, col); row grows with y, col with x'},
      'input_normalisation': {**networks.INPUT_NORMALISATION,
                              'where': 'inside the ONNX graph, after the rotation'},
      'onnx': {
          'file': 'model.onnx', 'opset': ONNX_OPSET, 'converter': 'jax2onnx',
          'inputs': [
              {'name': 'color', 'shape': [1, num_views, side, side, 3], 'dtype': 'float32',
               'meaning': 'colour heightmaps of every camera view, RGB in 0..1, [0, view, '
                          'row, col, channel], 0 where the view saw nothing; views outside '
                          'views_used are ignored'},
              {'name': 'depth', 'shape': [1, num_views, side, side], 'dtype': 'float32',
               'meaning': 'height above the table in metres, [0, view, row, col]; '
                          '0 where the view saw nothing'}],
          'outputs': [
              {'name': 'q', 'shape': [1, 2, k, side, side], 'dtype': 'float32',
               'meaning': 'Q[0, primitive, rotation, row, col] in the heightmap frame (already '
                          'turned back); a primitive the method lacks reads no_action; corners '
                          'that the rotation turns out of the square read 0'}],
          'in_graph': ['views_used selection', 'rotation of the inputs by -angle(k) for each '
                       'k (bilinear, zero fill)', 'input normalisation', 'the FCNs',
                       'rotation of the Q maps back by +angle(k)'],
          'outside_graph': ['the action rule and the argmax (action_rule)',
                            'pixel -> world (pixel_to_world)']},
  }


def export(workdir, out) -> dict[str, pathlib.Path]:
  """Writes params.npz, model.json and model.onnx of the latest checkpoint of `workdir` to `out`."""
  config, model, step = load(workdir)
  flat = flat_params(model)
  proto = onnx_model(config, model)
  out = pathlib.Path(out)
  out.mkdir(parents=True, exist_ok=True)
  paths = {'params': out / 'params.npz', 'model_json': out / 'model.json',
           'onnx': out / 'model.onnx'}
  np.savez(paths['params'], **flat)
  paths['model_json'].write_text(json.dumps(describe(config, flat, step, workdir), indent=1))
  paths['onnx'].write_bytes(proto.SerializeToString())
  return paths


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--checkpoint', required=True, help='work directory of a train.py run')
  parser.add_argument('--out', required=True, help='output folder')
  args = parser.parse_args(argv)
  try:
    paths = export(args.checkpoint, args.out)
  except ExportError as e:
    print(f'error: {e}', file=sys.stderr)
    return 2
  for path in paths.values():
    print(path)
  return 0


if __name__ == '__main__':
  sys.exit(main())
