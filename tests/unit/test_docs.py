"""The paths README.md and docs/ name exist, and the symbols README.md and the guides in docs/
name resolve: a file moved or a function renamed takes its mentions along. The results the pages
state are recomputed from the results.json they rest on."""
import dataclasses
import importlib
import json
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
TOP = ('mvcoba_jax/', 'tests/', 'docs/', 'examples/', 'benchmarks/', 'experiments/', 'pretrained/',
       '.ci/')
# `path`, optionally with :line or a trailing call; markdown links (target)
NAMED = re.compile(r'`([\w./-]+?)(?::\w+)?`|\]\(([^)#\s]+)')


def _documents():
  return [ROOT / 'README.md', *sorted((ROOT / 'docs').glob('*.md')),
          *sorted((ROOT / 'docs' / 'results').glob('*.md'))]


def _named(document: pathlib.Path):
  """(line number, path) for every repository path the document names: a code span starting at
  a top-level folder of the repository, or a relative markdown link (from the document)."""
  for number, line in enumerate(document.read_text().splitlines(), 1):
    for span, link in NAMED.findall(line):
      if span.startswith(TOP) and not any(c in span for c in '*<>{}'):
        yield number, ROOT / span
      elif link and '://' not in link and not link.startswith('mailto:'):
        yield number, document.parent / link


def test_every_path_the_docs_name_exists():
  missing = [f'{d.relative_to(ROOT)}:{n}: {p.relative_to(ROOT) if p.is_relative_to(ROOT) else p}'
             for d in _documents() for n, p in _named(d) if not p.exists()]
  assert not missing, '\n'.join(missing)


# `module.name[.attr...]`, optionally called: a symbol of the package, named by its module's last
# component (`runner.evaluate`), its full path (`mvcoba_jax.deploy.policy.choose`), or a config
# field (`train.replay_ratio`). Spans ending in a file extension are paths, checked above.
SYMBOL = re.compile(r'`([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+)(?:\([^`]*\))?`')
EXTENSIONS = {'py', 'json', 'jsonl', 'md', 'png', 'npz', 'onnx', 'scn', 'txt', 'csv', 'yaml', 'sh',
              'toml', 'mp4', 'log'}


def _has(obj, names) -> bool:
  """Whether `obj.a.b...` exists; a dataclass's fields count as its attributes."""
  for name in names:
    if isinstance(obj, type) and dataclasses.is_dataclass(obj) and name in {
        f.name for f in dataclasses.fields(obj)}:
      obj = object()
    elif hasattr(obj, name):
      obj = getattr(obj, name)
    else:
      return False
  return True


def _resolves(span: str, modules: dict[str, list[str]]) -> bool | None:
  """Whether a symbol span names something that exists; None when it names nothing of ours."""
  from mvcoba_jax.config import Config
  parts = span.split('.')
  if parts[-1] in EXTENSIONS:
    return None
  if parts[0] == 'mvcoba_jax':
    for i in range(len(parts), 0, -1):
      try:
        return _has(importlib.import_module('.'.join(parts[:i])), parts[i:])
      except ImportError:
        continue
  sections = {f.name: type(getattr(Config(), f.name)) for f in dataclasses.fields(Config)
              if dataclasses.is_dataclass(getattr(Config(), f.name))}
  if len(parts) == 2 and parts[0] in sections and _has(sections[parts[0]], parts[1:]):
    return True
  if parts[0] in modules:
    return any(_has(importlib.import_module(m), parts[1:]) for m in modules[parts[0]])
  return False if parts[0] in sections else None


def test_every_symbol_the_guides_name_resolves():
  modules = {}
  for path in (ROOT / 'mvcoba_jax').rglob('*.py'):
    parts = path.relative_to(ROOT).with_suffix('').parts
    name = '.'.join(parts[:-1] if parts[-1] == '__init__' else parts)
    modules.setdefault(name.split('.')[-1], []).append(name)
  wrong = [f'{d.relative_to(ROOT)}:{n}: {span}'
           for d in [ROOT / 'README.md', *sorted((ROOT / 'docs').glob('*.md'))]
           for n, line in enumerate(d.read_text().splitlines(), 1)
           for span in SYMBOL.findall(line) if _resolves(span, modules) is False]
  assert not wrong, '\n'.join(wrong)


def test_the_results_are_the_reproductions_tables():
  """reproduction.md holds mvcoba-reproduce's frozen comparison.md row for row and in order, and
  the README its compact summary of the same results (`paper.summary`): a new reproduction is
  not half taken over."""
  from mvcoba_jax.evaluation import paper, report
  folder = ROOT / 'docs' / 'results' / 'reproduction'
  page = [line for line in (ROOT / 'docs' / 'results' / 'reproduction.md').read_text().splitlines()
          if line.startswith('|')]
  rows = [line for line in (folder / 'comparison.md').read_text().splitlines()
          if line.startswith('|')]
  assert rows and any(page[i:i + len(rows)] == rows for i in range(len(page))), \
      'reproduction.md differs from ' + str(folder / 'comparison.md')
  results, readme = report.joined_report([str(folder)]), (ROOT / 'README.md').read_text()
  assert paper.summary(results) in readme, 'README.md results differ from the summary'
  if 'vpg' in results:
    assert paper.summary(results, suites=('vpg',), columns=paper.VPG_SUMMARY,
                         reference='VPG') in readme, \
        "README.md's VPG table differs from the summary"


def test_the_readme_is_for_users():
  lines = (ROOT / 'README.md').read_text().splitlines()
  assert len(lines) <= 150 and max(map(len, lines)) <= 120


# page -> the landed results (folders of results.json, joined) its separations rest on.
SEPARATION_PAGES = {
    'README.md': [('docs/results/reproduction',),
                  ('docs/results/recipe/winning/claim-short_push', 'docs/results/reproduction')],
    'docs/results/reproduction.md': [('docs/results/reproduction',),
                                     ('docs/results/reproduction/online',)],
    'docs/results/winning-policy.md': [('docs/results/recipe/winning/claim',
                                        'docs/results/reproduction'),
                                       ('docs/results/recipe/winning/claim-short_push',
                                        'docs/results/reproduction')],
}


def test_every_separation_a_page_states_is_recomputed_from_its_results():
  """Each 'A > B (gap N)' line, and each '(gap N' of the prose, in README.md and the pages of
  docs/results is recomputed from the results.json it rests on (`paper.comparisons` over the
  joined folders): a line to the letter, a gap to its digits. A page stating a gap without its
  results named in SEPARATION_PAGES fails, so no claim of 'A > B' goes unchecked."""
  import re

  from mvcoba_jax.evaluation import paper, report
  pages = [ROOT / 'README.md', *sorted((ROOT / 'docs' / 'results').glob('*.md'))]
  checked = 0
  for page in pages:
    text, name = page.read_text(), str(page.relative_to(ROOT))
    stated = re.findall(r'\(gap (\d+(?:\.\d+)?)', text)
    if not stated:
      continue
    assert name in SEPARATION_PAGES, f'{name} states gaps but names no results they rest on'
    computed = '\n'.join(paper.comparisons(report.joined_report([str(ROOT / f) for f in folders]))
                          for folders in SEPARATION_PAGES[name])
    lines = set(computed.splitlines())
    gaps = [float(g) for g in re.findall(r'\(gap (-?[\d.]+)\)', computed)]
    for line in text.splitlines():
      if line.startswith('- ') and ' > ' in line and '(gap' in line:
        assert line in lines, f'{name}: {line}'
    for gap in stated:
      digits = len(gap.partition('.')[2])
      assert any(round(g, digits) == float(gap) for g in gaps), f'{name}: gap {gap}'
      checked += 1
  assert checked >= 3


def _readme_paragraph(start: str) -> str:
  """The README paragraph that begins with `start`, its lines joined by single spaces."""
  text = (ROOT / 'README.md').read_text()
  return ' '.join(text[text.index(start):].split('\n\n')[0].split())


def _check_default_claim(text: str) -> None:
  """Every figure the README states of the default preset is recomputed from the claim it names
  (`recipe/winning/claim-short_push`, joined with the reproduction for the gaps): the grasp
  success intervals per suite and their suite, the share of objects picked, each gap over the
  reproduction's MV-COBA beside its suite, the seed count, the seeds' spread and the runs
  completed; so a changed figure, a gap moved to another suite or pair, or a direction turned
  fails."""
  from mvcoba_jax.evaluation import intervals, report
  claim = report.joined_report([str(ROOT / 'docs/results/recipe/winning/claim-short_push'),
                                str(ROOT / 'docs/results/reproduction')])
  ours = {suite: report.seed_intervals(rows, minimum=1) for suite, rows in claim.items()}
  default = {suite: next(e for m, e in entries.items() if m == 'mvcoba')
             for suite, entries in ours.items()}
  reproduction = {suite: next(e for m, e in entries.items() if m.startswith('mvcoba {'))
                  for suite, entries in ours.items()}
  whole = lambda ci: f'{ci[0]:.0f} [{ci[1]:.0f}, {ci[2]:.0f}]'
  words = {'random': 'on heaps', 'ordered': 'on packed blocks',
           'occluded': 'under held-out occluders', 'vpg': "on VPG's cases"}
  assert f'{default["random"]["seeds"]} seeds x 3000 actions' in text
  stated = ', '.join(f'{whole(default[s]["grasp_success"])} {words[s]}' for s in words)
  assert stated.replace(f', {whole(default["vpg"]["grasp_success"])}',
                        f' and {whole(default["vpg"]["grasp_success"])}') in text, stated
  picked = sorted(round(default[s]['objects_picked'][0]) for s in words)
  assert f'picking {picked[0]}-{picked[-1]} % of the objects' in text
  assert "its grasp success is above the comparison's MV-COBA" in text
  short = {'ordered': 'packed blocks', 'occluded': 'occluders', 'vpg': "VPG's cases"}
  for suite, name in short.items():
    high, low = default[suite]['grasp_success'], reproduction[suite]['grasp_success']
    assert intervals.separated(high, low, (5, 5)), suite
    assert f'{name} (gap {high[1] - low[2]:.2f})' in text, suite
  spread = max(abs(v - default[s]['grasp_success'][0])
               for s in words for v in default[s]['per_seed']['grasp_success'])
  assert spread < 6 and 'every seed within 6 points of the mean' in text
  completed = default['random']['per_seed']['completion']
  within = max(abs(v - default['random']['completion'][0]) for v in completed)
  assert f'within {within:.1f} on heaps' in text
  assert (f'{whole(default["random"]["completion"])} % of heap runs and '
          f'{whole(default["vpg"]["completion"])} % of VPG\'s clear the table') in text


def test_the_readmes_claim_of_the_default_preset_is_its_results():
  _check_default_claim(_readme_paragraph('**The default preset**'))


@pytest.mark.parametrize('stated, mutated', [
    ('(gap 3.55)', '(gap 3.75)'),  # another pair's gap (MVP's on the heaps)
    ('packed blocks (gap 3.55), occluders (gap 1.15)',
     'packed blocks (gap 1.15), occluders (gap 3.55)'),
    ('is above the comparison', 'is below the comparison'),
    ('94 [90, 99] on packed blocks', '95 [90, 99] on packed blocks'),
    ('5 seeds x 3000 actions', '4 seeds x 3000 actions'),
    ('picking 98-100 %', 'picking 97-100 %'),
    ('within 13.3 on heaps', 'within 8.7 on heaps'),
])
def test_a_changed_claim_of_the_default_preset_fails(stated, mutated):
  """The mutations a results sentence must not survive: a gap swapped with another pair's or
  suite's, a flipped direction, a changed figure, a wrong seed count, a range that no longer
  holds."""
  text = _readme_paragraph('**The default preset**')
  assert stated in text
  with pytest.raises(AssertionError):
    _check_default_claim(text.replace(stated, mutated))


def _table_rows(page: str, header: str) -> list[list[str]]:
  """The cells of the rows of the Markdown table of `page` whose header line starts with
  `header`; the header and its rule left out."""
  lines = (ROOT / page).read_text().splitlines()
  start = next(i for i, line in enumerate(lines) if line.startswith(header))
  rows = []
  for line in lines[start:]:
    if not line.startswith('|'):
      break
    rows.append([c.strip() for c in line.strip('|').split('|')])
  return rows[2:]


def _row_of(folder: str, suite: str, label: str = 'mvcoba') -> dict:
  from mvcoba_jax.evaluation import report
  return report.joined_report([str(ROOT / folder)])[suite][label]


def _lost(row) -> str:
  runs = [r for logs in row['runs'].values() for r in logs]
  return f'{sum(r["lost"] for r in runs)} ({sum(r["lost"] > 0 for r in runs)})'


def test_the_heap_creep_page_states_its_results():
  """Every cell of heap-creep.md's three tables is its benchmark's JSON or its evaluations'
  results, recomputed."""
  bench = json.loads((ROOT / 'docs/results/benchmark-heap-creep.json').read_text())['results']
  suites = iter(bench)
  suite = None
  for cells in _table_rows('docs/results/heap-creep.md', '| suite (objects in play)'):
    suite = next(suites) if cells[0] else suite
    row = bench[suite][cells[1]]
    t = row['total']
    assert cells[2:] == [str(t['slid_1cm']), str(t['slid_5cm']), str(t['left']),
                         f'{row["physics_time_ratio"]:.2f}'], cells
  frozen = {'without': 'docs/results/pretrained-mvcoba/frozen',
            'noslip 3': 'docs/results/heap-creep/frozen-noslip3'}
  for cells in _table_rows('docs/results/heap-creep.md', '| suite (runs)'):
    suite, protocol = cells[0].split(' ')[0], cells[0].split(', ')[1]
    row = _row_of(frozen[protocol], suite)
    m = row['mean']
    assert cells[1:] == [f'{m["grasp_success"]:.1f}', f'{m["completion"]:.1f}',
                         f'{m["objects_picked"]:.1f}', _lost(row)], cells
  evals = {'cut_default': 'docs/results/generalise/eval',
           'noslip': 'docs/results/heap-creep/screen/eval'}
  for cells in _table_rows('docs/results/heap-creep.md', '| variant, seed'):
    variant, seed = cells[0].strip('`').split('`, ')
    folder = f'{evals[variant]}/{variant}-s{seed}'
    packed, heaps, high = (_row_of(folder, f'docs/results/validation/{s}')
                           for s in ('val-packed', 'val-heaps', 'val-occluded-high'))
    assert cells[1:] == [
        f'{packed["mean"]["grasp_success"]:.1f} / {packed["mean"]["completion"]:.1f}',
        f'{heaps["mean"]["grasp_success"]:.1f} / {heaps["mean"]["completion"]:.1f} / '
        f'{_lost(heaps)}', f'{high["mean"]["grasp_success"]:.1f}'], cells


def test_the_per_shape_table_of_the_gripper_page_is_its_results():
  rows = {'RG2': 'mvcoba (cut_default/mvcoba-s20)',
          '2F-85': 'mvcoba (gripper_robotiq_2f85/mvcoba-s20)'}
  checked = 0
  for cells in _table_rows('docs/results/gripper.md', '| suite, shape'):
    suite, shape = cells[0].split(', ')
    shape = shape.split(' (')[0].replace(' ', '_')
    for label, cell in zip(rows.values(), cells[1:]):
      m = _row_of('docs/results/gripper/shapes', suite, label)['by_shape'][shape]
      assert cell == f'{m["grasp_success"]:.1f} ({m["grasps"]}), {m["pushes"]} pushes', cells
      checked += 1
  assert checked == 14


def test_the_per_object_table_of_the_objects_page_is_its_results():
  """objects.md's per-object table: the shipped default's counts on `novel` and the grasp
  ceiling of each everyday object, recomputed."""
  shapes = _row_of('docs/results/objects/shipped-novel-shapes', 'novel')['by_shape']
  ceiling = json.loads((ROOT / 'docs/results/objects/grasp-ceiling-everyday.json').read_text())
  rows = _table_rows('docs/results/objects.md', '| object | objects in the runs')
  for cells in rows:
    name = f'package:sim/objects/everyday/{cells[0].replace(" ", "_")}'
    m = shapes[name]
    assert cells[1:] == [str(m['objects']), f'{m["objects_picked"]:.1f}',
                         f'{m["grasp_success"]:.1f} ({m["grasps"]})', str(m['pushes']),
                         f'{ceiling["rg2"]["shapes"][name]["fraction"]:.2f}'], cells
  assert len(rows) == len(shapes) - 1  # every object but the actions at no object
