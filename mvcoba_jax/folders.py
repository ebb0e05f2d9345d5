"""Output folders that commands write: one process at a time, and nothing replaced unasked.

A command takes `claim(folder, ...)` before it writes there: the folder is created (where a link
names it), locked for the life of the process (an advisory `fcntl` lock on `.lock`, released by
the kernel however the process ends, so a killed run leaves no stale lock), and refused when it
holds results of an earlier invocation that the command would replace, unless the user said so.
"""
from __future__ import annotations

import ctypes
import errno
import fcntl
import glob
import os
import pathlib
import shutil
import tempfile

from mvcoba_jax.config import Error

LOCK_NAME = '.lock'
_held: dict[pathlib.Path, object] = {}  # folder -> its open lock file, kept for the process


class FolderError(Error):
  """A folder that cannot be written: not a folder, in use, or holding results to keep."""


def check(folder, earlier: tuple[str, ...] = (), keep: bool = False, overwrite: bool = False,
          keep_flag: str | None = '--resume') -> pathlib.Path:
  """What `claim` would refuse, found without creating or changing anything: a file in the
  folder's place, a folder that another process holds, or one that holds any of `earlier` (the
  files an earlier invocation leaves) when neither `keep` nor `overwrite` says what to do."""
  path = pathlib.Path(folder)
  if path.exists() and not path.is_dir():
    raise FolderError(f'{path} is a file, not a folder')
  if not path.is_dir():  # it would be made (where a link points): its nearest parent must take it
    parent = next(p for p in path.resolve().parents if p.exists())
    if not parent.is_dir():
      raise FolderError(f'{path}: {parent} is a file, not a folder')
    _writable(parent, path)
    return path
  _writable(path, path)
  if path.resolve() not in _held and (path / LOCK_NAME).exists():  # none: nobody holds it
    _lock(path).close()  # closing the file releases the lock
  found = [name for name in earlier if (path / name).exists()]
  if found and not keep and not overwrite:
    keeping = f'{keep_flag} to keep them, ' if keep_flag else ''
    raise FolderError(f'{path} holds results of an earlier run ({", ".join(found)}); pass '
                      f'{keeping}--overwrite to replace them, or choose another folder')
  return path


def _writable(folder: pathlib.Path, named: pathlib.Path) -> None:
  """FolderError unless a file can be made in `folder`: a probe made and removed at once, since
  `os.access` says yes to root on file systems that refuse every write (/proc, read-only
  mounts)."""
  try:
    with tempfile.TemporaryFile(dir=folder):
      pass
  except OSError as e:
    raise FolderError(f'{named}: {folder} is not writable ({e.strerror})') from None


def claim(folder, earlier: tuple[str, ...] = (), keep: bool = False, overwrite: bool = False,
          keep_flag: str | None = '--resume') -> pathlib.Path:
  """`folder`, created and locked for this process, after `check`; with `overwrite` (and not
  `keep`) the `earlier` files it holds are deleted first."""
  path = check(folder, earlier, keep, overwrite, keep_flag)
  try:
    path.resolve().mkdir(parents=True, exist_ok=True)
  except OSError as e:
    raise FolderError(f'{path}: {e.strerror}') from None
  key = path.resolve()
  if key not in _held:
    lock_file = _lock(path)
    lock_file.seek(0)
    lock_file.truncate()
    lock_file.write(f'{os.getpid()}\n')
    lock_file.flush()
    _held[key] = lock_file
  if not keep:
    for name in earlier:
      target = path / name
      if target.is_dir():
        shutil.rmtree(target)
      elif target.exists():
        target.unlink()
  return path


def _lock(path: pathlib.Path):
  """The folder's lock file, open and locked by this process; FolderError when another holds
  it or it cannot be opened."""
  try:
    lock_file = open(path / LOCK_NAME, 'a+')  # noqa: SIM115 (the caller keeps or closes it)
  except OSError as e:
    raise FolderError(f'{path}: {e.strerror}') from None
  try:
    fcntl.flock(lock_file, fcntl.LOCK_EX | fcntl.LOCK_NB)
  except OSError as e:
    lock_file.close()
    if isinstance(e, BlockingIOError):
      raise FolderError(f'{path} is in use by another mvcoba-jax process; wait for it to end or '
                        'choose another folder') from None
    raise FolderError(f'{path}: {e.strerror}') from None
  return lock_file


def release(folder) -> None:
  """Unlocks a folder this process claimed (a process's locks also end with it)."""
  lock_file = _held.pop(pathlib.Path(folder).resolve(), None)
  if lock_file is not None:
    lock_file.close()


def replace_whole(folder, contents: dict[str, bytes]) -> None:
  """Writes `contents` (file name -> bytes) as `folder`'s new whole set of those files, at once:
  they go to a staging folder beside it (on the same file system, with every other entry of the
  folder copied in and its lock file linked, so the lock the caller holds stays on the folder),
  which is then exchanged with `folder` by one atomic rename (Linux's renameat2 RENAME_EXCHANGE;
  elsewhere two renames, a window of microseconds). A kill or a full disk at any moment leaves
  `folder` holding the old set or the new one, never a mix; the staging folders a killed writer
  left are removed by the next. A symbolic link is followed: the folder it names is replaced.
  The caller holds the folder (`claim`). OSError when writing fails, with `folder` untouched and
  the staging folder removed."""
  folder = pathlib.Path(folder).resolve()
  for left in folder.parent.glob(f'.{glob.escape(folder.name)}.staging-*'):
    if not _alive(left.name.rpartition('-')[2]):
      shutil.rmtree(left, ignore_errors=True)
  staging = folder.with_name(f'.{folder.name}.staging-{os.getpid()}')
  shutil.rmtree(staging, ignore_errors=True)
  try:
    staging.mkdir()
    for entry in (folder.iterdir() if folder.is_dir() else ()):
      if entry.name in contents:
        continue
      if entry.name == LOCK_NAME:
        os.link(entry, staging / entry.name)
      elif entry.is_dir() and not entry.is_symlink():
        shutil.copytree(entry, staging / entry.name, symlinks=True)
      elif entry.is_file() or entry.is_symlink():
        shutil.copy2(entry, staging / entry.name, follow_symlinks=False)
      else:
        raise OSError(errno.EINVAL, 'not a file, folder or link, which cannot be kept', str(entry))
    for name, data in contents.items():
      with open(staging / name, 'wb') as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    if folder.is_dir():
      _exchange(staging, folder)  # staging now holds the old set
    else:
      os.rename(staging, folder)
  finally:
    shutil.rmtree(staging, ignore_errors=True)


def _alive(pid: str) -> bool:
  """Whether the process of this id (a staging folder's suffix) runs; False for no number."""
  if not pid.isdigit():
    return False
  try:
    os.kill(int(pid), 0)
  except ProcessLookupError:
    return False
  except OSError:  # another user's process
    return True
  return True


_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


def _exchange(a: pathlib.Path, b: pathlib.Path) -> None:
  """Swaps two folders' names atomically where the kernel can (renameat2), else by two renames."""
  try:
    renameat2 = ctypes.CDLL(None, use_errno=True).renameat2
  except (OSError, AttributeError):
    renameat2 = None
  if renameat2 is not None:
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
      return
    code = ctypes.get_errno()
    if code not in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):
      raise OSError(code, os.strerror(code), str(b))
  parked = b.with_name(b.name + '.old')
  os.rename(b, parked)
  os.rename(a, b)
  os.rename(parked, a)
