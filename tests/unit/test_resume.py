"""A resumed training refuses a config other than the one it started with, naming the fields,
before anything compiles or is written (`api.resumable`)."""
import json

import pytest

from mvcoba_jax import api
from mvcoba_jax.config import override, resolve, to_dict


@pytest.fixture()
def run(tmp_path):
  """A work directory as a training leaves it at action 400: its config and a checkpoint."""
  config = resolve('tiny', ['train.total_actions=800'])
  (tmp_path / 'config.json').write_text(json.dumps(to_dict(config)))
  (tmp_path / 'checkpoints' / '400').mkdir(parents=True)
  return config, tmp_path


def test_resume_refuses_another_recipe_naming_each_field(run):
  config, workdir = run
  changed = override(override(config, 'train.learning_rate=0.5'), 'train.gamma=0.9')
  with pytest.raises(api.TrainError) as error:
    api.resumable(changed, workdir)
  message = str(error.value)
  assert 'train.learning_rate=0.0001 -> 0.5' in message and 'train.gamma=0.5 -> 0.9' in message
  assert '\n' not in message and (workdir / 'config.json').read_text() == json.dumps(
      to_dict(config))


def test_resume_may_train_longer_save_and_compute_elsewhere_but_not_less_than_done(run):
  config, workdir = run
  for field in ('train.total_actions=1600', 'train.checkpoint_every=3',
                'scene.backend=native', 'scene.native_threads=1'):
    api.resumable(override(config, field), workdir)
  with pytest.raises(api.TrainError, match='total_actions=8 is below the 400 actions'):
    api.resumable(override(config, 'train.total_actions=8'), workdir)


def test_resume_with_an_unreadable_config_is_one_line(run):
  config, workdir = run
  (workdir / 'config.json').write_text('{')
  with pytest.raises(api.TrainError, match='cannot read the run\'s config'):
    api.resumable(config, workdir)
