"""The paths README.md and docs/ name exist: a file moved or renamed takes its mentions along."""
import pathlib
import re

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
  summary = paper.summary(report.joined_report([str(folder)]))
  assert summary in (ROOT / 'README.md').read_text(), 'README.md results differ from the summary'


def test_the_readme_is_for_users():
  lines = (ROOT / 'README.md').read_text().splitlines()
  assert len(lines) <= 150 and max(map(len, lines)) <= 120
