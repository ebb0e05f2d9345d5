"""A trained Q-network as a policy: read from a training work directory (its latest checkpoint)
or from a folder that `mvcoba-export` wrote (model.json, params.npz), which travels without the
training state."""
from __future__ import annotations

import hashlib
import json
import pathlib
import typing
import warnings

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx

from mvcoba_jax import arguments, perception
from mvcoba_jax import config as config_lib
from mvcoba_jax.config import Config, Error
from mvcoba_jax.deploy import checks, model_file
from mvcoba_jax.deploy.calibration import DeployError
from mvcoba_jax.deploy.policy import Action
from mvcoba_jax.sim.contract import filled
from mvcoba_jax.learner import agent, networks
from mvcoba_jax.sim.geometry import rotation_angle
from mvcoba_jax.sim.contract import push_length
from mvcoba_jax.learner.checkpoint import CheckpointError, Checkpoints, incompatibilities

PARAM_LIMIT = 1e6  # no trained weight comes near this; a larger one is damage, not learning


class PolicyError(Error):
  """A folder that holds no usable policy; the message names the path or config keys."""


class Policy(typing.NamedTuple):
  """A trained policy: its config, Q-network and training step (it unpacks as that triple), and
  the action its method's rule takes on an observation (`act`), as evaluation takes it."""
  config: Config
  network: networks.QNetwork
  step: int

  def q_maps(self, color, depth) -> np.ndarray:
    """(2, K, R, R) Q maps (push, grasp) of one observation: colour (V, R, R, 3) in 0..1 and
    height above the table (V, R, R) in m of every camera's heightmap."""
    return np.asarray(self.network(jnp.asarray(color, jnp.float32)[None],
                                   jnp.asarray(depth, jnp.float32)[None])[0])

  def act(self, color, depth, changed: bool = True, seen=None) -> Action:
    """The greedy action on one observation (`q_maps`' arguments): the method's rule picks the
    primitive (MV-COBA's: grasp when the last action changed the scene, `changed`, else push;
    model.json's `action_rule` says each method's) and the argmax rotation and cell of its map.
    `seen` (V, R, R) bool, which cells each view saw, is needed by a policy trained with
    `perception.fill_unseen`, which fills each view's unseen cells from the others as training
    did (`perception.Observation.seen`). The action is the one record a robot takes
    (`deploy.Action`), here in the workspace frame: its position the cell's centre at the highest
    surface the method's views see there, its angle anticlockwise from +x.

    The observation is checked before the network and the action after it (`deploy.checks`, as
    `deploy.OnnxPolicy.act` checks them): PolicyError names what is refused (another grid or
    number of views, heights not in metres, colour out of its range, a view the network reads
    that saw nothing by `seen`, a non-finite score or a position off the workspace); non-finite
    cells count as unseen (0)."""
    config, method = self.config, self.network.method
    top, half = config.scene.workspace_top, config.scene.workspace_half
    if not isinstance(changed, (bool, np.bool_)):
      raise PolicyError(f'changed={changed!r}: True or False (did the last action change the '
                        'scene)')
    try:
      color, depth = checks.observation(color, depth, len(config.scene.cameras),
                                        perception.grid_size(config.perception, config.scene), top)
      if seen is not None or config.perception.fill_unseen:
        seen = checks.seen(seen, depth)
        checks.sighted(seen, method.views)
      if config.perception.fill_unseen:
        color, depth = filled(color, depth, seen)
    except checks.Refused as e:
      raise PolicyError(f'observation refused: {e}') from None
    depth = jnp.asarray(depth)[None]
    pick, score = agent.Decision.of(method, config).act(
        jnp.asarray(self.q_maps(color, depth[0]))[None], depth, jnp.asarray([bool(changed)]))
    world = agent.to_world(pick, depth, method.views, config.perception.heightmap_resolution,
                           half)
    k, grasp = int(pick.rotation[0]), int(pick.primitive[0]) == agent.GRASP
    angle = float(rotation_angle(k, config.env.num_rotations))
    position = (float(world.x[0]), float(world.y[0]), float(world.z[0]))
    action = Action(
        primitive='grasp' if grasp else 'push', position=position, angle=angle,
        push_length=0.0 if grasp else float(push_length(position[:2], angle,
                                                        config.env.push_length, half)),
        opening=config.scene.gripper.max_opening if grasp else 0.0, rotation=k,
        row=int(pick.row[0]), col=int(pick.col[0]), q=float(score[0]))
    try:
      checks.action(action.q, action.angle, action.position, half, top)
    except checks.Refused as e:
      raise PolicyError(f'action refused: {e}') from None
    return action


def _config(saved: dict, path: pathlib.Path) -> Config:
  """The config of a saved run's JSON; warns about fields it lacks, which take today's defaults."""
  config = config_lib.from_dict(saved, where=str(path))
  defaulted = config_lib.defaulted(saved, config)
  if defaulted:  # e.g. a run from before scene.contact_timeconst trained with other physics
    warnings.warn(f'{path} lacks fields added since it was written; they take the current '
                  f'defaults: {", ".join(f"{k}={v!r}" for k, v in defaulted.items())} '
                  '(add them to it if its run used other values)', stacklevel=3)
  return config


def fingerprint(model: networks.QNetwork) -> str:
  """A short hash of the network's parameters: tells apart two policies with the same path and
  step (a run trained again into the same folder)."""
  digest = hashlib.sha256()
  for leaf in jax.tree.leaves(nnx.state(model, nnx.Param)):
    digest.update(np.asarray(leaf).tobytes())
  return digest.hexdigest()[:16]


def load(workdir) -> Policy:
  """The `Policy` (config, Q-network, step) of the latest checkpoint in a training work
  directory, or of a folder that `export` wrote (model.json, params.npz: see `load_exported`).

  For a work directory the config (config.json) is checked against the checkpoint's, then the
  network's parameters alone are read (`Checkpoints.restore_params`): no scene, physics, replay
  or optimiser is built or read.
  """
  workdir = arguments.path('mvcoba_jax.load_policy', 'workdir', workdir)
  if (workdir / 'model.json').is_file():
    return load_exported(workdir)
  config_path = workdir / 'config.json'
  if not config_path.is_file():
    raise PolicyError(f'{config_path} does not exist: --checkpoint takes the work directory of '
                      'an mvcoba-train run (config.json, checkpoints/) or a folder written by '
                      'mvcoba-export (model.json, params.npz)')
  if not (workdir / 'checkpoints').is_dir():  # Checkpoints() would create it
    raise PolicyError(f'no checkpoints in {workdir / "checkpoints"}')
  try:
    config = _config(json.loads(config_path.read_text()), config_path)
  except (ValueError, TypeError, RecursionError) as e:  # bad JSON or values that misfit fields
    raise PolicyError(f'{config_path}: {e}') from None
  checkpoints = Checkpoints(workdir)
  step = checkpoints.latest()
  if step is None:
    raise PolicyError(f'no checkpoint in {checkpoints.directory}')
  where = checkpoints.directory / str(step)
  try:
    problems = incompatibilities(checkpoints.meta(step)['config'], config_lib.to_dict(config),
                                 where)
  except CheckpointError as e:
    raise PolicyError(str(e)) from None
  if problems:
    raise PolicyError(f'{config_path} does not match checkpoint {where}:\n  '
                      + '\n  '.join(problems))
  try:
    model = networks.build_network(config.network, config.env.num_rotations, nnx.Rngs(0))
  except ValueError as e:  # an unknown method or trunk
    raise PolicyError(f'{config_path}: {e}') from None
  graphdef, like = nnx.split(model)
  try:
    params = checkpoints.restore_params(like, step)
  except CheckpointError as e:
    raise PolicyError(str(e)) from None
  except (ValueError, KeyError) as e:  # the network code changed since
    raise PolicyError(f'checkpoint {where} does not fit the network of {config_path}: {e}'
                      ) from None
  model = nnx.merge(graphdef, params)
  bad = [n for n, a in flat_params(model).items() if not np.isfinite(a).all()]
  if bad:
    raise PolicyError(f'checkpoint {where}: parameters hold NaN or infinite values '
                      f'({", ".join(bad[:3])}{", ..." if len(bad) > 3 else ""})')
  return Policy(config, model, step)


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


def _described(spec: model_file.ModelFile, config: Config):
  """(key, what model.json says, what its own config gives) of the fields model.json derives
  from its config: a hand-edited config that the ONNX graph and the arrays were not made for
  disagrees with them."""
  side = round(2 * config.scene.workspace_half / config.perception.heightmap_resolution)
  return [('method', spec.method, config.network.method),
          ('rotations.num_rotations', spec.num_rotations, config.env.num_rotations),
          ('heightmap.grid_size', spec.grid_size, side),
          ('heightmap.num_views', spec.num_views, len(config.scene.cameras))]


def load_exported(folder) -> Policy:
  """The `Policy` (config, Q-network, step) from what `export` wrote: a trained policy without
  its training state (replay, optimiser), small enough to ship, as `pretrained/` does.

  Every parameter must be in params.npz with the shape the network of model.json's config
  expects; otherwise the error names the arrays that differ.
  """
  folder = pathlib.Path(folder)
  model_path, params_path = folder / 'model.json', folder / 'params.npz'
  try:
    spec = model_file.read(folder)
  except DeployError as e:
    raise PolicyError(str(e)) from None
  step = spec.checkpoint_step
  try:
    config = _config(spec.config, model_path)
    untied = [f'{key} {value!r} (its config gives {own!r})'
              for key, value, own in _described(spec, config) if value != own]
    if untied:
      raise ValueError('its description and its config disagree: ' + '; '.join(untied))
    model = networks.build_network(config.network, config.env.num_rotations, nnx.Rngs(0))
  except (OSError, ValueError, TypeError, KeyError, AttributeError, RecursionError) as e:
    raise PolicyError(f'{model_path}: not an export of mvcoba_jax ({type(e).__name__}: {e})'
                      ) from None
  want = {n: (a.shape, a.dtype) for n, a in flat_params(model).items()}
  try:
    with np.load(params_path, allow_pickle=False) as saved:
      got = {n: saved[n] for n in saved.files}
  except Exception as e:  # noqa: BLE001 (a damaged zip raises BadZipFile, EOFError, zlib.error...)
    raise PolicyError(f'{params_path}: cannot read it: {type(e).__name__}: {e}') from None
  both = sorted(set(want) & set(got))
  problems = ([f'{n}: missing' for n in sorted(set(want) - set(got))]
              + [f'{n}: not a parameter of this network' for n in sorted(set(got) - set(want))]
              + [f'{n}: shape {got[n].shape}, the network needs {want[n][0]}'
                 for n in both if got[n].shape != want[n][0]]
              + [f'{n}: dtype {got[n].dtype}, the network needs {want[n][1]}'
                 for n in both if got[n].dtype != want[n][1]]
              + [f'{n}: holds NaN or infinite values' for n in both
                 if got[n].dtype == want[n][1] and not np.isfinite(got[n]).all()]
              + [f'{n}: holds values beyond +-{PARAM_LIMIT:g}' for n in both
                 if got[n].dtype == want[n][1] and np.isfinite(got[n]).all()
                 and got[n].size and np.abs(got[n]).max() > PARAM_LIMIT])
  if problems:
    raise PolicyError(f'{params_path} does not fit the {config.network.method} network of '
                      f'{model_path}:\n  ' + '\n  '.join(problems[:10]))

  def filled(tree, prefix):
    return {k: filled(v, f'{prefix}{k}/') if isinstance(v, dict)
            else jnp.asarray(got[f'{prefix}{k}']) for k, v in tree.items()}

  state = nnx.state(model)
  nnx.replace_by_pure_dict(state, filled(nnx.to_pure_dict(state), ''))
  nnx.update(model, state)
  return Policy(config, model, step)
