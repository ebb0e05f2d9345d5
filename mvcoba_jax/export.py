"""Exports a trained Q-network for use outside JAX.

`export(workdir, out)` (`mvcoba-export --checkpoint WORKDIR --out DIR`) takes a training work
directory (config.json, checkpoints/) and writes the following to DIR; `policy.load` reads it back
(`mvcoba-eval --checkpoint DIR`), so a trained policy travels without its training state:
- params.npz: the network parameters by flat name (`fcns/0/trunk/blocks/0/conv1/kernel`);
- model.onnx: the whole decision on one state: the Q-network forward for all K rotations,
  rotations included, and the method's action rule and argmax (`agent.Decision`), given whether
  the last action changed the scene;
- model.json: names, shapes and dtypes of the parameters, the config, the heightmap frame, the
  rotations, the input normalisation, the method's action rule in words and what the ONNX graph
  leaves to the caller (pixel -> world, the change observation), all that
  `examples/onnx_infer.py` needs;
  with `results`, the figures that evaluations measured for these parameters, so a shipped
  policy says what it scores and `mvcoba-eval` can check it.
"""
from __future__ import annotations

import dataclasses
import io
import json
import logging
import pathlib

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx

from mvcoba_jax import folders, methods, perception
from mvcoba_jax import config as config_lib
from mvcoba_jax.config import Config
from mvcoba_jax.learner import agent, networks
from mvcoba_jax.deploy import DeployError, model_file
from mvcoba_jax.sim.contract import BELOW_TABLE, HEIGHT_UNIT
from mvcoba_jax.policy import PolicyError, fingerprint, flat_params, load
from mvcoba_jax.sim import shapes
from mvcoba_jax.sim.geometry import rotation_angle
from mvcoba_jax.sim.primitives import GRASP, PUSH

ONNX_OPSET = 23


def onnx_model(config: Config, model: networks.QNetwork):
  """ModelProto of (color (1, V, R, R, 3), depth (1, V, R, R), changed (1,) bool) -> q
  (1, 2, K, R, R), the rule's scores where it suppresses, action (1, 4) int32 (primitive,
  rotation, row, col) and value (1,): `agent.Decision.act`, traced, so a runtime applies no rule."""
  # jax2onnx's plugins for dm_pix, which the network does not use, fail to import under this
  # JAX and log a traceback each; they are skipped either way.
  logging.getLogger('jax2onnx.plugins.plugin_system').setLevel(logging.ERROR)
  try:
    from jax2onnx import (
      to_onnx,  # a dev extra: the rest of this module works without it
    )
  except ImportError as e:
    raise PolicyError(f'model.onnx needs jax2onnx ({e}); pip install -e ".[dev]"') from None

  graphdef, params = nnx.split(model)
  side, views = perception.grid_size(config.perception, config.scene), len(config.scene.cameras)
  method = model.method
  decision = agent.Decision.of(method, config)

  def forward(color, depth, changed):  # `Decision.act`, its rule's maps kept as an output
    q = nnx.merge(graphdef, params)(color, depth)
    maps = decision.maps(q, depth)
    action, value = agent.greedy(maps, changed, method)
    chosen = jnp.stack([action.primitive, action.rotation, action.row, action.col], axis=-1)
    return (q, *((maps,) if decision.suppress else ()), chosen, value)

  try:
    return to_onnx(forward, [jax.ShapeDtypeStruct((1, views, side, side, 3), jnp.float32),
                             jax.ShapeDtypeStruct((1, views, side, side), jnp.float32),
                             jax.ShapeDtypeStruct((1,), jnp.bool_)],
                   model_name=f'mvcoba_{method.name}_q', opset=ONNX_OPSET,
                   input_names=['color', 'depth', 'changed'],
                   output_names=list(output_names(decision.suppress)))
  except Exception as e:  # noqa: BLE001 (the converter raises any kind on what it cannot trace)
    raise PolicyError(f'method {method.name}: its decision does not convert to ONNX '
                      f'({type(e).__name__}: {str(e)[:160]}); a Rule\'s pick must avoid '
                      'what jax2onnx cannot trace (methods.Rule)') from None


def output_names(suppress: bool) -> tuple[str, ...]:
  """The graph's outputs: Q maps, where the rule suppresses the scores it compares, the action
  and its value."""
  return ('q', 'score', 'action', 'value') if suppress else ('q', 'action', 'value')


def action_rule(method: methods.Method, suppress: bool = False) -> dict:
  """The method's `Rule` in words, applied inside the graph; its maps are the scores where it
  suppresses (`agent.Decision.suppress`)."""
  maps = 'score' if suppress or method.suppress else 'q'
  return {'name': method.rule.name, 'maps': maps, 'primitive': method.rule.text,
          'pixel': (f'argmax of that primitive\'s {maps} over (rotation, row, col), flattened in '
                    'that order; the first maximum wins'),
          'where': 'inside the ONNX graph (its action output); changed is its input',
          'greedy': 'exploration (epsilon-greedy) is a training matter and is not exported'}


def describe(config: Config, method: methods.Method, params: dict[str, np.ndarray], step: int,
             workdir, commit: str | None = None, measured: dict | None = None) -> dict:
  """The content of model.json of a network of `method` trained in `config`; `commit` names the
  code that trained it when known, `measured` is `figures`' answer."""
  spec = model_file_of(config, method, step)
  side, k, num_views = spec.grid_size, spec.num_rotations, spec.num_views
  suppress = agent.Decision.of(method, config).suppress
  half = spec.workspace_half_m
  described = {
      'format': model_file.FORMAT,
      'source': {'workdir': str(pathlib.Path(workdir).resolve()), 'seed': config.seed,
                 'commit': commit},
      'figures': measured or {},
      'network': dataclasses.asdict(config.network),
      'objects': {'trained_on': shapes.pool_record(config.scene.pool),
                  'meaning': 'the object slots of training\'s scene: the VPG blocks by name, '
                             'mesh objects by path and the SHA-256 of their files'},
      'params': {'file': 'params.npz',
                 'arrays': {n: {'shape': list(a.shape), 'dtype': str(a.dtype)}
                            for n, a in params.items()},
                 'naming': 'the Flax NNX state path joined by "/" (list indices as numbers)'},
      'no_action': networks.NO_ACTION,
      'action_rule': action_rule(method, suppress),
      'rotations': {'formula': 'angle(k) = k * 2 * pi / num_rotations',
                    'meaning': ('rotation index k: the yaw of the gripper and the push '
                                'direction, counter-clockwise from +x (col) towards +y (row)')},
      'heightmap': {'workspace_bounds_m': {'x': [-half, half], 'y': [-half, half]},
                    'height_meaning': ('heights in steps of height_unit_m; points below '
                                       'below_table_m are not the table\'s and are dropped')},
      'pixel_to_world': {'x': 'x = -workspace_half_m + (col + 0.5) * resolution_m',
                         'y': 'y = -workspace_half_m + (row + 0.5) * resolution_m',
                         'z': 'z = max over views_used of depth[view, row, col]',
                         'meaning': 'the centre of cell (row, col); row grows with y, col with x'},
      'input_normalisation': {**networks.INPUT_NORMALISATION,
                              'where': 'inside the ONNX graph, after the rotation'},
      'onnx': {
          'opset': ONNX_OPSET, 'converter': 'jax2onnx',
          'inputs': [
              {'name': 'color', 'shape': [1, num_views, side, side, 3], 'dtype': 'float32',
               'meaning': 'colour heightmaps of every camera view, RGB in 0..1, [0, view, '
                          'row, col, channel], 0 where the view saw nothing; views outside '
                          'views_used are ignored'},
              {'name': 'depth', 'shape': [1, num_views, side, side], 'dtype': 'float32',
               'meaning': 'height above the table in metres, [0, view, row, col]; '
                          '0 where the view saw nothing'},
              {'name': 'changed', 'shape': [1], 'dtype': 'bool',
               'meaning': 'whether the last action changed the scene (true before the first '
                          'action): the change observation, outside the graph'}],
          'outputs': [
              {'name': 'q', 'shape': [1, 2, k, side, side], 'dtype': 'float32',
               'meaning': 'Q[0, primitive, rotation, row, col] in the heightmap frame (already '
                          'turned back); a primitive the method lacks reads no_action; corners '
                          'that the rotation turns out of the square read 0'}] + ([
              {'name': 'score', 'shape': [1, 2, k, side, side], 'dtype': 'float32',
               'meaning': 'what the action rule compares: (Q + 0.1) x the suppression factor '
                          'of each action (CPG), no_action where suppressed; Q where nothing '
                          'is allowed'}] if suppress else []) + [
              {'name': 'action', 'shape': [1, 4], 'dtype': 'int32',
               'meaning': '[primitive, rotation, row, col] of the greedy action (action_rule)'},
              {'name': 'value', 'shape': [1], 'dtype': 'float32',
               'meaning': f'the {action_rule(method, suppress)["maps"]} of that action'}],
          'in_graph': ['views_used selection'] + (
              ['fusion of the views into one, the highest point per cell'] if method.fuse else []) + [
                  'rotation of the inputs by -angle(k) for each k (bilinear, zero fill)',
                  'input normalisation', 'the FCNs', 'rotation of the Q maps back by +angle(k)'
              ] + (['suppression of actions that cannot act (score)'] if suppress else []) + [
                  'the action rule and the argmax (action_rule)'],
          'outside_graph': ['pixel -> world (pixel_to_world)',
                            'the change observation between two frames (config.perception)'
                            ] + (['filling each view\'s unseen cells from the others '
                                  '(config.perception.fill_unseen)']
                                 if config.perception.fill_unseen else [])},
  }
  return _merged(described, model_file.as_json(spec))


def model_file_of(config: Config, method: methods.Method, step: int) -> model_file.ModelFile:
  """What a runtime reads from the model.json of a `method` network trained in `config` for
  `step` actions (`deploy.model_file`: written and read through the same fields)."""
  k = config.env.num_rotations
  p = config.perception
  return model_file.ModelFile(
      graph_decides=True, push=PUSH, grasp=GRASP, num_rotations=k,
      angles_rad=tuple(rotation_angle(np.arange(k), k).tolist()),
      resolution_m=p.heightmap_resolution, grid_size=perception.grid_size(p, config.scene),
      workspace_half_m=config.scene.workspace_half, num_views=len(config.scene.cameras),
      views_used=method.views, height_unit_m=HEIGHT_UNIT, below_table_m=BELOW_TABLE,
      onnx_file='model.onnx', change_min=p.change_min, change_max=p.change_max,
      change_area=p.change_area, failed_grasp_changes=p.failed_grasp_changes,
      failed_grasp_retries=p.failed_grasp_retries,
      fill_unseen=p.fill_unseen, push_length_m=config.env.push_length,
      gripper=json.loads(json.dumps(dataclasses.asdict(config.scene.gripper))),
      method=method.name, checkpoint_step=step,
      config=json.loads(json.dumps(config_lib.to_dict(config))))  # as the file holds it


def _merged(described: dict, fields: dict) -> dict:
  """`described` with the contract's `fields` set in their sections; a field it already holds
  must have the same value (the config's perception settings are both)."""
  out = dict(described)
  for key, value in fields.items():
    if isinstance(value, dict):
      out[key] = _merged(out.get(key, {}), value)
    elif key in out and out[key] != value:
      raise RuntimeError(f'model.json: {key} written twice, {out[key]!r} and {value!r}')
    else:
      out[key] = value
  return out


def figures(results, model: networks.QNetwork) -> dict:
  """protocol -> suite -> the mean figures (and the runs behind them) of every row of these
  results.json files that evaluated `model`'s parameters (`policy.fingerprint`), with the
  `--set` overrides each was measured under (`set`: [] where the policy acted as it trained).
  Raises PolicyError naming the file that cannot be read, that holds no such row, or that
  measures one protocol and suite twice with different figures or overrides."""
  mine, found = fingerprint(model), {}
  for path in map(pathlib.Path, results):
    try:
      report = json.loads(path.read_text())
      rows = [(str(row['settings'].get('protocol', 'frozen')), suite, {
          **row['mean'], 'cases': len(row['settings']['cases']),
          'runs_per_case': row['settings']['runs'], 'max_actions': row['settings']['max_actions'],
          'seed': row['settings']['seed'], 'set': list(row['settings'].get('set', [])),
          'results': str(path)})
              for suite, by_label in report.items() for row in by_label.values()
              if row['settings'].get('params') == mine]
    except (OSError, ValueError, TypeError, KeyError, AttributeError) as e:
      raise PolicyError(f'{path}: not the results.json of an mvcoba-eval '
                        f'({type(e).__name__}: {e})') from None
    if not rows:
      raise PolicyError(f'{path}: no row evaluated these parameters (fingerprint {mine})')
    for protocol, suite, figure in rows:
      known = found.setdefault(protocol, {}).get(suite)
      if known is not None and {**known, 'results': ''} != {**figure, 'results': ''}:
        raise PolicyError(f'{path}: {protocol} {suite} measured again with other figures or '
                          f'overrides (--set {figure["set"]}) than in {known["results"]} '
                          f'(--set {known["set"]})')
      found[protocol][suite] = figure
  return found


EXPORT_FILES = ('params.npz', 'model.json', 'model.onnx')


def export(workdir, out, results=(), commit: str | None = None,
           overwrite: bool = False) -> dict[str, pathlib.Path]:
  """Writes params.npz, model.json and model.onnx of the latest checkpoint of `workdir` to `out`;
  model.json carries the figures of the `results` files' rows for these parameters (`figures`)
  and `commit`, the code that trained it, when given. An `out` holding an export is refused
  unless `overwrite` (checked again once the folder is held: of two exports into one new folder
  at once, the later is refused); the folder is held (`folders.claim`) from then until its three
  files are replaced at once (`folders.replace_whole`, into the folder a link names): a kill or a
  full disk leaves the old export or the new one, never a mix.

  Raises PolicyError for a checkpoint or results that cannot serve, a model.json that its
  readers would refuse (read back through `deploy.model_file` first), or an `out` that cannot be
  written, before anything is written.
  """
  try:
    folders.check(out, EXPORT_FILES, overwrite=overwrite, keep_flag=None)
  except folders.FolderError as e:
    raise PolicyError(str(e)) from None
  config, model, step = load(workdir)
  measured = figures(results, model)
  flat = flat_params(model)
  proto = onnx_model(config, model)
  try:
    model_json = json.dumps(describe(config, model.method, flat, step, workdir, commit,
                                     measured), indent=1, allow_nan=False)
    model_file.checked(json.loads(model_json), pathlib.Path(out) / 'model.json')  # as read back
  except DeployError as e:  # a field its readers refuse
    raise PolicyError(f'{workdir}: its export would be refused by its readers ({e})') from None
  except ValueError as e:  # a non-finite number
    raise PolicyError(f'{workdir}: model.json would hold {e}') from None
  try:  # held from here to the exchange; checked again, as another export may have ended since
    out = folders.claim(out)
    folders.check(out, EXPORT_FILES, overwrite=overwrite, keep_flag=None)
  except folders.FolderError as e:
    folders.release(out)
    raise PolicyError(str(e)) from None
  try:
    buffer = io.BytesIO()
    np.savez(buffer, **flat)
    folders.replace_whole(out, {'params.npz': buffer.getvalue(),
                                'model.json': model_json.encode(),
                                'model.onnx': proto.SerializeToString()})
  except OSError as e:
    where = f'{e.filename}: ' if e.filename else ''
    raise PolicyError(f'{out}: cannot write the export ({where}{e.strerror or e}); what it held '
                      'is kept') from None
  finally:
    folders.release(out)
  return {'params': out / 'params.npz', 'model_json': out / 'model.json',
          'onnx': out / 'model.onnx'}
