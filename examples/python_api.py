"""Trains, evaluates and plots from Python, with the calls the commands make: the tiny preset
trained for a few hundred actions, evaluated on the occluded suite, its loss and grasp success
plotted over training. About two minutes on a 2-core CPU.

  python examples/python_api.py [--workdir runs/python_api] [--actions 128]
"""
from __future__ import annotations

import argparse
import json
import pathlib
import sys

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402

import mvcoba_jax  # noqa: E402
from mvcoba_jax.config import resolve  # noqa: E402


def main(argv=None) -> int:
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--workdir', default='runs/python_api')
  parser.add_argument('--actions', type=int, default=128, help='training actions')
  args = parser.parse_args(argv)
  workdir = pathlib.Path(args.workdir)

  # Any preset with any field overridden, as `--config tiny --set ...` would.
  config = resolve('tiny', [f'train.total_actions={args.actions}',
                            f'train.epsilon_decay_actions={args.actions}'])
  result = mvcoba_jax.train(config, workdir / 'train', overwrite=True, eval_actions=4)
  print(f'trained {int(result.state.actions)} actions: {result.summary}')

  # The occluded suite, 2 runs per case, each run capped at 10 actions.
  report = mvcoba_jax.evaluate([result.workdir], ['occluded'], runs=2, max_actions=10,
                               out=workdir / 'eval', overwrite=True, progress=False)
  for label, row in report['occluded'].items():
    print(f'{label} on the occluded suite: ' + ', '.join(
        f'{name} {value:.1f}' for name, value in row['mean'].items()))

  # metrics.jsonl holds one line per compiled call of training.
  lines = [json.loads(line) for line in (result.workdir / 'metrics.jsonl').read_text().splitlines()]
  fig, axes = plt.subplots(1, 2, figsize=(8, 3))
  for ax, key in zip(axes, ('loss', 'grasp_success')):
    ax.plot([m['actions'] for m in lines], [m[key] for m in lines])
    ax.set_xlabel('training actions')
    ax.set_title(key)
  fig.tight_layout()
  fig.savefig(workdir / 'training.png')
  print(f'wrote {workdir / "training.png"}')

  # The trained network alone, without a scene, a physics backend or a replay.
  config, network, step = mvcoba_jax.load_policy(result.workdir)
  print(f'loaded {config.network.method} at action {step}')
  return 0


if __name__ == '__main__':
  sys.exit(main())
