"""Checkpoints of the whole training state with Orbax: atomic, resumable, shape-checked.

Orbax writes each step into a temporary folder and renames it when complete, so a run killed
mid-save leaves the previous checkpoint intact. Beside the state we keep a JSON of the resolved
config and the host counters; a checkpoint is only restored into a run whose network, scene and
batch shapes match, otherwise the differing keys are named.
"""
from __future__ import annotations

import json
import pathlib

import jax
import orbax.checkpoint as ocp

from mvcoba_jax import config as config_lib
from mvcoba_jax.config import Error

# Config sections that fix the shapes of the saved state; they must match to resume.
SHAPE_KEYS = ('scene', 'perception', 'network', 'num_envs', 'train.replay_capacity',
              'env.num_objects', 'env.num_rotations')


class CheckpointError(Error):
  """A checkpoint that is missing or cannot be restored into this run."""


def _lookup(flat: dict, key: str) -> dict:
  return {k: v for k, v in flat.items() if k == key or k.startswith(key + '.')}


def incompatibilities(saved: dict, current: dict, where) -> list[str]:
  """Human-readable differences in the shape-defining config keys (both as JSON would hold them).

  Fields that `saved` lacks (added since it was written) take their defaults, as they do when
  its run's config.json is loaded; `where` names the checkpoint in errors."""
  try:
    saved = config_lib.to_dict(config_lib.from_dict(saved))
  except config_lib.ConfigError as e:
    raise CheckpointError(f'checkpoint {where}: its saved config: {e}') from None
  a, b = (config_lib.flat(json.loads(json.dumps(d))) for d in (saved, current))
  problems = []
  for key in SHAPE_KEYS:
    sa, sb = _lookup(a, key), _lookup(b, key)
    problems += [f'{k}: checkpoint {sa.get(k)!r}, this run {sb.get(k)!r}'
                 for k in sorted(set(sa) | set(sb)) if sa.get(k) != sb.get(k)]
  return problems


def _name(path) -> str:
  """`env.sim.qpos`, `params.fcns.0.trunk.blocks.0.conv1.kernel.value`: a leaf's tree path. The
  task state's fields (`TrainState.task`) keep the names they had at the top of the training
  state, so checkpoints written before it existed still restore."""
  name = jax.tree_util.keystr(path, simple=True, separator='.')
  return name[len('task.'):] if name.startswith('task.') else name


def _leaves(state) -> dict:
  """The state's non-empty arrays by tree path (Orbax cannot save zero-size arrays). Named, not
  numbered: a state whose structure changed fails to restore instead of filling its fields
  with another field's values of the same shape."""
  return {_name(path): leaf for path, leaf in jax.tree_util.tree_flatten_with_path(state)[0]
          if leaf.size}


def latest_step(workdir) -> int | None:
  """The step of a training work directory's latest completed checkpoint, None without one;
  looks without creating."""
  folder = pathlib.Path(workdir) / 'checkpoints'
  steps = [int(p.name) for p in folder.iterdir()
           if p.is_dir() and p.name.isdigit()] if folder.is_dir() else []
  return max(steps, default=None)


def holds_checkpoint(workdir) -> bool:
  """Whether a training work directory holds a completed checkpoint; looks without creating."""
  return latest_step(workdir) is not None


class Checkpoints:
  """The checkpoints of one work directory."""

  def __init__(self, directory: str | pathlib.Path, max_to_keep: int = 2):
    self.directory = pathlib.Path(directory).resolve() / 'checkpoints'
    self.manager = ocp.CheckpointManager(
        self.directory, item_names=('state', 'meta'),
        options=ocp.CheckpointManagerOptions(max_to_keep=max_to_keep, create=True,
                                             enable_async_checkpointing=False))

  def latest(self) -> int | None:
    return self.manager.latest_step()

  def save(self, step: int, state, meta: dict) -> None:
    self.manager.save(step, args=ocp.args.Composite(state=ocp.args.StandardSave(_leaves(state)),
                                                    meta=ocp.args.JsonSave(meta)))
    self.manager.wait_until_finished()

  def meta(self, step: int | None = None) -> dict:
    step = self._step(step)
    meta = self._read(step, meta=ocp.args.JsonRestore())['meta']
    if not isinstance(meta, dict) or not isinstance(meta.get('config'), dict):
      raise CheckpointError(f'checkpoint {self.directory / str(step)}: its meta holds no config')
    return meta

  def restore(self, like, config, step: int | None = None):
    """(state, meta) of `step` (default: the latest), checked against `config` first."""
    step = self._step(step)
    meta = self.meta(step)
    problems = incompatibilities(meta['config'], config_lib.to_dict(config),
                                 self.directory / str(step))
    if problems:
      raise CheckpointError(f'checkpoint {self.directory / str(step)} was written by a run of '
                            'another shape; it cannot be resumed here:\n  ' + '\n  '.join(problems))
    abstract = jax.tree.map(ocp.utils.to_shape_dtype_struct, _leaves(like))
    restored = self._read(step, state=ocp.args.StandardRestore(abstract))['state']
    paths, treedef = jax.tree_util.tree_flatten_with_path(like)
    return jax.tree.unflatten(treedef, [restored.get(_name(path), leaf)
                                        for path, leaf in paths]), meta

  def restore_params(self, params, step: int | None = None):
    """The network parameters alone of `step` (default: the latest), shaped like `params` (the
    `params` field of the training state): what a policy needs, read without the replay,
    optimiser or environments (Orbax's partial restore)."""
    step = self._step(step)
    abstract = jax.tree.map(ocp.utils.to_shape_dtype_struct, _leaves({'params': params}))
    restored = self._read(step, state=ocp.args.PyTreeRestore(
        abstract, restore_args=ocp.checkpoint_utils.construct_restore_args(abstract),
        partial_restore=True))['state']
    paths, treedef = jax.tree_util.tree_flatten_with_path({'params': params})
    missing = [_name(path) for path, leaf in paths if leaf.size and _name(path) not in restored]
    if missing:
      raise CheckpointError(f'checkpoint {self.directory / str(step)} lacks network parameters '
                            f'({", ".join(missing[:3])})')
    return jax.tree.unflatten(treedef, [restored.get(_name(path), leaf)
                                        for path, leaf in paths])['params']

  def _read(self, step: int, **items):
    """Orbax's restore of `items`; whatever is wrong with the files becomes one CheckpointError
    naming the step folder (Orbax raises many kinds for missing, truncated or garbled files)."""
    try:
      return self.manager.restore(step, args=ocp.args.Composite(**items))
    except Exception as e:  # noqa: BLE001
      problem = str(e).splitlines()[0][:200] if str(e) else ''
      raise CheckpointError(f'checkpoint {self.directory / str(step)} cannot be read: '
                            f'{type(e).__name__}: {problem}') from None

  def _step(self, step):
    step = self.latest() if step is None else step
    if step is None:
      raise CheckpointError(f'no checkpoint in {self.directory}')
    return step
