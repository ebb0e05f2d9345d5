"""`mvcoba-train --distributed`: two processes on this machine, one CPU device each, train as one.

Each process steps its own environment of the tiny preset's two; they join through
`jax.distributed.initialize` (gloo collectives on the CPU). Process 0 alone writes the logs; both
write their shards of the checkpoint; both see the whole batch's actions.
"""
import json
import os
import pathlib
import socket
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]


def free_port() -> int:
  with socket.socket() as s:
    s.bind(('localhost', 0))
    return s.getsockname()[1]


def test_two_processes_train_as_one(tmp_path):
  workdir = tmp_path / 'run'
  port = free_port()
  env = dict(os.environ)
  env.pop('XLA_FLAGS', None)
  processes = [subprocess.Popen(
      [sys.executable, '-m', 'mvcoba_jax.cli.train', '--config', 'tiny', '--set', 'train.total_actions=4',
       '--eval-actions', '1', '--json', '--workdir', str(workdir), '--distributed',
       '--coordinator', f'localhost:{port}', '--num-processes', '2', '--process-id', str(i)],
      cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
      for i in range(2)]
  outputs = [p.communicate(timeout=1500)[0] for p in processes]
  for p, out in zip(processes, outputs):
    assert p.returncode == 0, out[-3000:]
  summaries = [next(line for line in out.splitlines() if line.startswith('training: {'))
               .split(';')[0] for out in outputs]
  assert summaries[0] == summaries[1]  # both processes saw every environment's actions
  records = [json.loads(line) for line in (workdir / 'actions.jsonl').read_text().splitlines()]
  assert [r['action'] for r in records] == [0, 1, 2, 3] and {r['env'] for r in records} == {0, 1}
  assert json.loads(summaries[0].removeprefix('training: '))['actions'] == 4
  assert (workdir / 'curves.png').is_file() and (workdir / 'checkpoints' / '4').is_dir()
