"""The package's shape: the simulator imports nothing above it, the learner nothing of evaluation
or of the commands, evaluation nothing of the commands, no module imports itself back,
importing changes nothing in the process, and the built wheel carries presets, suites and the
command-line entry points."""
import ast
import pathlib
import shutil
import subprocess
import sys
import zipfile

import mvcoba_jax

PACKAGE = pathlib.Path(mvcoba_jax.__file__).resolve().parent
ROOT = PACKAGE.parent


def _module_name(path: pathlib.Path) -> str:
  parts = path.relative_to(ROOT).with_suffix('').parts
  return '.'.join(parts[:-1] if parts[-1] == '__init__' else parts)


def _imports() -> dict[str, set[str]]:
  """Module -> the mvcoba_jax modules it imports anywhere in its body."""
  modules = {_module_name(p): p for p in PACKAGE.rglob('*.py')}
  graph = {}
  for name, path in modules.items():
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
      if isinstance(node, ast.Import):
        found |= {a.name for a in node.names}
      elif isinstance(node, ast.ImportFrom) and node.module:
        found |= {f'{node.module}.{a.name}' if f'{node.module}.{a.name}' in modules
                  else node.module for a in node.names}
    graph[name] = {m for m in found if m in modules and m != name}
  return graph


def test_simulator_imports_nothing_above_it():
  outside = {m: sorted(d for d in deps if not d.startswith('mvcoba_jax.sim'))
             for m, deps in _imports().items() if m.startswith('mvcoba_jax.sim')}
  assert not any(outside.values()), outside


# group -> the modules above it, which it must not import
ABOVE = {
    'mvcoba_jax.learner': ('mvcoba_jax.evaluation', 'mvcoba_jax.api', 'mvcoba_jax.cli',
                           'mvcoba_jax.reproduction', 'mvcoba_jax.policy', 'mvcoba_jax.export'),
    'mvcoba_jax.evaluation': ('mvcoba_jax.api', 'mvcoba_jax.cli', 'mvcoba_jax.reproduction'),
}


def test_groups_import_nothing_above_them():
  graph = _imports()
  assert any(m.startswith('mvcoba_jax.learner.') for m in graph)
  assert any(m.startswith('mvcoba_jax.evaluation.') for m in graph)
  wrong = {m: sorted(d for d in deps if d.startswith(ABOVE[group]))
           for group in ABOVE for m, deps in graph.items() if m.startswith(group)}
  assert not any(wrong.values()), wrong


def test_no_import_cycles():
  graph, state, cycles = _imports(), {}, []

  def visit(module, path):
    state[module] = 'open'
    for dep in sorted(graph[module]):
      if state.get(dep) == 'open':
        cycles.append(path[path.index(dep):] + [dep] if dep in path else [module, dep])
      elif dep not in state:
        visit(dep, path + [dep])
    state[module] = 'done'

  for module in sorted(graph):
    if module not in state:
      visit(module, [module])
  assert not cycles, cycles


def test_importing_every_module_leaves_the_process_as_it_was():
  """No compilation cache, BLAS threads as they were, nothing printed (MJX's warp lines dropped):
  only `runtime.setup()` changes the process."""
  names = sorted(_imports())
  code = ('import importlib, jax, scipy.linalg, threadpoolctl\n'
          'before = [lib["num_threads"] for lib in threadpoolctl.threadpool_info()]\n'
          f'for m in {names!r}: importlib.import_module(m)\n'
          'assert jax.config.jax_compilation_cache_dir is None, jax.config.jax_compilation_cache_dir\n'
          'after = [lib["num_threads"] for lib in threadpoolctl.threadpool_info()]\n'
          'assert after[:len(before)] == before, (before, after)\n')
  out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, timeout=300,
                       env={'PATH': '/usr/bin:/bin', 'JAX_PLATFORMS': 'cpu'})
  assert out.returncode == 0, out.stderr[-2000:]
  assert out.stdout == ''


def test_wheel_carries_presets_suites_and_entry_points(tmp_path):
  source = tmp_path / 'source'  # a copy: building writes build/ beside the sources
  source.mkdir()
  for name in ('pyproject.toml', 'README.md', 'LICENSE'):
    shutil.copy(ROOT / name, source)
  shutil.copytree(PACKAGE, source / 'mvcoba_jax', ignore=shutil.ignore_patterns('__pycache__'))
  subprocess.run([sys.executable, '-m', 'pip', 'wheel', '--no-deps', '-q', '-w', str(tmp_path),
                  str(source)], check=True, capture_output=True, timeout=600)
  wheel, = tmp_path.glob('mvcoba_jax-*.whl')
  names = zipfile.ZipFile(wheel).namelist()
  for suite, count in (('random', 6), ('ordered', 8), ('packed-ring', 4), ('packed-t_shape', 4),
                       ('packed-stack', 4), ('occluded', 12), ('isolated', 16),
                       ('dev-random', 6), ('dev-ordered', 6), ('dev-occluded', 12),
                       ('novel', 8)):
    assert sum(n.startswith(f'mvcoba_jax/suites/{suite}/') and n.endswith('.scn')
               for n in names) == count, suite
  assert sum(n.startswith('mvcoba_jax/suites/vpg/test-10-obj-') for n in names) == 11
  assert 'mvcoba_jax/suites/manifest.json' in names
  shipped = {str(p.relative_to(ROOT)) for p in (PACKAGE / 'sim' / 'objects').rglob('*.*')}
  assert shipped and shipped <= set(names)  # the object sets the novel suite and presets name
  assert {'mvcoba_jax/presets/default.py', 'mvcoba_jax/presets/tiny.py',
          'mvcoba_jax/sim/tabletop.py', 'mvcoba_jax/suites/vpg/LICENSE-vpg'} <= set(names)
  assert not any(n.startswith(('tests/', 'benchmarks/')) for n in names)
  entry_points = next(n for n in names if n.endswith('entry_points.txt'))
  text = zipfile.ZipFile(wheel).read(entry_points).decode()
  for command in ('mvcoba-train', 'mvcoba-eval', 'mvcoba-export', 'mvcoba-viz', 'mvcoba-demo',
                  'mvcoba-reproduce'):
    assert f'{command} = mvcoba_jax.cli.' in text, command
