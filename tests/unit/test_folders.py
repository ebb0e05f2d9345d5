"""Output folders: one process at a time, nothing replaced unasked, and the commands' refusals,
all before anything is compiled."""
import json
import os
import subprocess
import sys
import time

import pytest

from mvcoba_jax import folders
from mvcoba_jax.cli import eval as eval_cli
from mvcoba_jax.cli import train as train_cli


def test_a_folder_with_earlier_results_is_kept_replaced_or_refused(tmp_path):
  out = tmp_path / 'out'
  folders.claim(out, ('results.json',))
  (out / 'results.json').write_text('{}')
  folders.release(out)
  with pytest.raises(folders.FolderError, match=r'results.json\); pass --resume to keep them, '
                                                '--overwrite to replace them'):
    folders.claim(out, ('results.json',))
  assert (out / 'results.json').read_text() == '{}'
  folders.claim(out, ('results.json',), keep=True)
  assert (out / 'results.json').exists()
  folders.release(out)
  folders.claim(out, ('results.json',), overwrite=True)
  assert not (out / 'results.json').exists()
  folders.release(out)
  (tmp_path / 'file').write_text('')
  with pytest.raises(folders.FolderError, match='is a file, not a folder'):
    folders.claim(tmp_path / 'file')


def test_a_folder_in_use_by_another_process_is_refused_until_it_ends(tmp_path):
  holder = subprocess.Popen(
      [sys.executable, '-c', 'import sys, time\nfrom mvcoba_jax import folders\n'
       f'folders.claim({str(tmp_path / "w")!r})\nprint("held", flush=True)\ntime.sleep(60)'],
      stdout=subprocess.PIPE, text=True)
  try:
    assert holder.stdout.readline().strip() == 'held'
    with pytest.raises(folders.FolderError, match='in use by another mvcoba-jax process'):
      folders.check(tmp_path / 'w')
    code = train_cli.main(['--config', 'tiny', '--workdir', str(tmp_path / 'w')])
    assert code == 2
  finally:
    holder.kill()
    holder.wait()
  time.sleep(0.1)
  folders.claim(tmp_path / 'w')  # a killed holder leaves no stale lock
  folders.release(tmp_path / 'w')


def test_commands_refuse_to_replace_earlier_results_before_compiling(tmp_path, capsys):
  run = tmp_path / 'run'
  run.mkdir()
  (run / 'actions.jsonl').write_text('{"action": 0}\n')  # an earlier run without a checkpoint
  started = time.perf_counter()
  assert train_cli.main(['--config', 'tiny', '--workdir', str(run)]) == 2
  assert 'actions.jsonl); pass --resume' in capsys.readouterr().err
  assert (run / 'actions.jsonl').read_text() == '{"action": 0}\n'
  out = tmp_path / 'eval'
  out.mkdir()
  (out / 'results.json').write_text(json.dumps({'random': {}}))
  assert eval_cli.main(['--baseline', 'heuristic', '--suite', 'isolated', '--config', 'tiny',
                        '--out', str(out)]) == 2
  assert 'results.json); pass --resume' in capsys.readouterr().err
  assert json.loads((out / 'results.json').read_text()) == {'random': {}}
  assert eval_cli.main(['--tables', str(out), '--out', str(out)]) == 2
  assert '--overwrite to replace them' in capsys.readouterr().err
  assert time.perf_counter() - started < 20  # refused before any compile


@pytest.mark.parametrize('argv, says', [
    (['--max-actions', '1000000000000'], '--max-actions 1000000000000: allowed range [1, 10000]'),
    (['--runs', '1000000000'], '--runs 1000000000 x 16 cases of suite isolated'),
    (['--runs', '0'], '--runs 0 x 16 cases'),
])
def test_evaluation_work_is_bounded_before_anything_loads(tmp_path, capsys, argv, says):
  assert eval_cli.main(['--baseline', 'heuristic', '--suite', 'isolated', '--config', 'tiny',
                        '--out', str(tmp_path / 'o'), *argv]) == 2
  assert says in capsys.readouterr().err and not (tmp_path / 'o').exists()


def test_a_results_file_that_cannot_be_written_leaves_the_earlier_one(tmp_path):
  """A file size limit (as a full disk would) refuses the new results.json: one line says so and
  the earlier file is as it was."""
  (tmp_path / 'results.json').write_text('{"earlier": 1}')
  code = ('import resource, signal, pathlib\n'
          'from mvcoba_jax.evaluation import report\n'
          'signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n'
          'resource.setrlimit(resource.RLIMIT_FSIZE, (64, 64))\n'
          'try:\n'
          f'  report.write_whole(pathlib.Path({str(tmp_path / "results.json")!r}), "x" * 4096)\n'
          'except report.ResultsError as e:\n'
          '  print(e)\n')
  out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, timeout=120)
  assert 'results.json (File too large); the earlier one is intact' in out.stdout, out.stderr
  assert (tmp_path / 'results.json').read_text() == '{"earlier": 1}'
  assert not list(tmp_path.glob('.*.partial'))


def test_a_folder_replaced_whole_stays_held_follows_its_link_and_clears_dead_staging(tmp_path):
  """The exchange keeps the writer's lock on the folder (another process is refused until the
  writer ends), writes into the folder a link names (the link stays), removes the staging folder
  a killed writer left, and refuses a FIFO it cannot keep in one OSError that names it."""
  real, link = tmp_path / 'real', tmp_path / 'link'
  link.symlink_to(real, target_is_directory=True)
  (tmp_path / '.real.staging-999999999').mkdir()  # a dead writer's: no such process
  probe = ('from mvcoba_jax import folders\ntry:\n'
           f'  folders.check({str(link)!r})\n  print("free")\n'
           'except folders.FolderError as e:\n  print(e)\n')
  folders.claim(link)
  try:
    folders.replace_whole(link, {'model.json': b'1'})
    folders.replace_whole(link, {'model.json': b'2'})
    held = subprocess.run([sys.executable, '-c', probe], capture_output=True, text=True,
                          timeout=120).stdout
  finally:
    folders.release(link)
  assert 'in use by another mvcoba-jax process' in held
  assert link.is_symlink() and (real / 'model.json').read_bytes() == b'2'
  assert sorted(p.name for p in tmp_path.iterdir()) == ['link', 'real']
  os.mkfifo(real / 'pipe')
  folders.claim(real)
  try:
    with pytest.raises(OSError, match='not a file, folder or link') as e:
      folders.replace_whole(real, {'model.json': b'3'})
  finally:
    folders.release(real)
  assert e.value.filename == str(real / 'pipe') and (real / 'model.json').read_bytes() == b'2'
  assert sorted(p.name for p in tmp_path.iterdir()) == ['link', 'real']
  assert subprocess.run([sys.executable, '-c', probe], capture_output=True, text=True,
                        timeout=120).stdout.strip() == 'free'


@pytest.mark.parametrize('blocks, says', [
    (['vgp=mvcoba'], "'vgp' is not an evaluated suite"),
    (['vpg=mvcoba=x'], 'expected [SUITE=]TABLE'),
    (['mvcoba', 'mvcoba'], "names 'every suite' twice"),
    (['nope'], 'expected [SUITE=]TABLE with TABLE one of'),
])
def test_block_tables_name_a_suite_evaluated_and_a_known_table(tmp_path, capsys, blocks, says):
  assert eval_cli.main(['--baseline', 'heuristic', '--suite', 'vpg', '--config', 'tiny',
                        '--out', str(tmp_path / 'o'), '--blocks', *blocks]) == 2
  assert says in capsys.readouterr().err


def test_a_block_table_for_a_suite_of_our_case_files_is_refused(tmp_path, capsys):
  assert eval_cli.main(['--baseline', 'heuristic', '--suite', 'ordered', '--config', 'tiny',
                        '--out', str(tmp_path / 'o'), '--blocks', 'mvcoba']) == 2
  assert 'VPG-format (.txt) cases; no evaluated suite has one' in capsys.readouterr().err


def test_a_long_error_is_cut_to_short_lines(capsys):
  from mvcoba_jax.cli import fail
  assert fail('x' * 100_000 + '\n' + 'y\n' * 50) == 2
  err = capsys.readouterr().err
  assert max(map(len, err.splitlines())) <= 307 and err.count('\n') == 21
  assert err.rstrip().endswith('and 31 more lines')


def test_reproduction_refuses_what_its_evaluation_would_before_training(tmp_path, capsys):
  from mvcoba_jax.cli import reproduce
  started = time.perf_counter()
  for argv, says in ((['--runs', '1000000000'], '--runs 1000000000 x 12 cases of suite occluded'),
                     (['--max-actions', '0'], '--max-actions 0: allowed range'),
                     (['--workdir', str(tmp_path / 'file')], 'is a file, not a folder'),
                     (['--out', str(tmp_path / 'file' / 'x')], 'file is a file, not a folder'),
                     (['--out', '/proc/mvcoba'], '/proc is not writable'),
                     (['--workdir', str(tmp_path / 'w'), '--out', str(tmp_path / 'w' / 'r')],
                      'lies in workdir'),
                     (['--workdir', str(tmp_path / 'w'), '--out', str(tmp_path / 'w')],
                      'lies in workdir')):
    (tmp_path / 'file').write_text('')
    assert reproduce.main(['--config', 'tiny', '--suites', 'occluded', '--out',
                           str(tmp_path / 'out'), '--workdir', str(tmp_path / 'sweep'),
                           *argv]) == 2
    assert says in capsys.readouterr().err
  assert time.perf_counter() - started < 20 and not (tmp_path / 'sweep').exists()


@pytest.mark.parametrize('command, argv, says', [
    ('demo', ['--actions', '-1'], '--actions -1: at least 1'),
    ('eval', ['--tables', 'a', '--online'], 'give it without --checkpoint, --baseline, --online'),
    ('train', ['--config', 'tiny', '--seeds', '0', '0', '--workdir', 'x'], 'given twice'),
    ('train', ['--config', 'tiny', '--eval-actions', '-5', '--workdir', 'x'], 'eval_actions=-5'),
])
def test_commands_refuse_nonsense_in_one_line(tmp_path, capsys, monkeypatch, command, argv, says):
  import importlib
  monkeypatch.chdir(tmp_path)
  main = importlib.import_module(f'mvcoba_jax.cli.{command}').main
  try:
    code = main(argv)
  except SystemExit as e:  # argparse's refusal
    code = e.code
  assert code == 2 and says in capsys.readouterr().err
  assert list(tmp_path.iterdir()) == []


def test_files_where_folders_go_are_refused_before_anything_compiles(tmp_path, capsys):
  from mvcoba_jax.cli import train as train_cli
  from mvcoba_jax.cli import viz as viz_cli
  started = time.perf_counter()
  run = tmp_path / 'run'
  run.mkdir()
  (run / 'tensorboard').write_text('not a folder')
  assert train_cli.main(['--config', 'tiny', '--workdir', str(run), '--overwrite']) == 2
  assert 'tensorboard is a file' in capsys.readouterr().err
  assert sorted(p.name for p in run.iterdir()) == ['tensorboard']
  case = tmp_path / 'one.scn'
  case.write_text('cube red 0 0 0\n')
  for argv in (['--out', str(case)], ['--save-state', str(case / 'state.npz')]):
    with pytest.raises(SystemExit) as exit_:
      viz_cli.main([str(case), '--config', 'tiny', *argv])
    assert exit_.value.code == 2 and 'is a file, not a folder' in capsys.readouterr().err
  assert time.perf_counter() - started < 20
