"""Generated bad results.json files (fixed seed) given to `mvcoba-eval --tables`: each is
answered by a clean refusal (exit 2, one short line) or a correct acceptance, never a traceback."""
import copy
import json
import random

from mvcoba_jax.cli import eval as eval_cli

RUN = {'actions': 6, 'grasp_attempts': 5, 'grasp_successes': 4, 'objects': 4, 'picked': 4,
       'lost': 0, 'completed': True, 'repeated_failures': 1}
VALID = {'ordered': {'mvcoba': {'wall_s': 3.0, 'runs': {'c0': [RUN, dict(RUN, completed=False,
                                                                          picked=2)]}}}}
ODD = [None, 'x', -1, 2 ** 40, 1.5, True, [], {}, [[[]]], float('inf'), '\u00e9' * 50]


def _mutants(rng: random.Random):
  """Bad variants of VALID: a value swapped for an odd one at a random place, a key dropped or
  added, counts that do not fit, truncations, undecodable bytes and deep nesting."""
  for _ in range(150):
    data = copy.deepcopy(VALID)
    log = data['ordered']['mvcoba']['runs']['c0'][rng.randrange(2)]
    kind = rng.randrange(5)
    if kind == 0:
      log[rng.choice(sorted(log))] = rng.choice(ODD)
    elif kind == 1:
      del log[rng.choice(sorted(log))]
    elif kind == 2:
      log[rng.choice(['extra', 'seed', ''])] = 1
    elif kind == 3:
      log['grasp_successes'] = log['grasp_attempts'] + rng.randrange(1, 100)
    else:
      target = rng.choice([data, data['ordered'], data['ordered']['mvcoba']])
      target[rng.choice(sorted(target))] = rng.choice(ODD)
    yield json.dumps(data).encode()
  text = json.dumps(VALID).encode()
  for cut in rng.sample(range(1, len(text)), 20):
    yield text[:cut]
  yield b'\xff\xfe' + text
  yield b'[' * 100_000 + b']' * 100_000
  yield b'{"ordered": ' * 5000 + b'{}' + b'}' * 5000


def test_fuzzed_results_are_refused_in_one_line_or_accepted(tmp_path, capsys):
  rng = random.Random(0)
  outcomes = {0: 0, 2: 0}
  for i, content in enumerate(_mutants(rng)):
    folder = tmp_path / f'in{i}'
    folder.mkdir()
    (folder / 'results.json').write_bytes(content)
    code = eval_cli.main(['--tables', str(folder), '--out', str(tmp_path / f'out{i}')])
    err = capsys.readouterr().err
    assert code in outcomes, (content[:200], err)
    outcomes[code] += 1
    if code == 2:
      assert err.startswith('error: ') and err.count('\n') == 1 and len(err) < 400, err
  assert outcomes[2] > 100 and outcomes[0] > 0, outcomes


def test_rows_that_do_not_fit_their_own_settings_are_refused_naming_the_field(tmp_path, capsys):
  """The issue's tampered rows, each refused by --tables in one line that names the field; the
  untouched row is accepted."""
  settings = {'cases': ['c0'], 'runs': 2, 'max_actions': 10, 'listed_objects': {'c0': 4}}
  good = copy.deepcopy(VALID)
  good['ordered']['mvcoba']['settings'] = settings
  tampered = [
      (lambda r: r['settings'].update(cases=['c0', 'c9']), 'settings.cases'),
      (lambda r: r['settings'].update(runs=3), '2 runs where its settings say 3'),
      (lambda r: r['settings'].update(max_actions=1), 'more actions than the cap of 1'),
      (lambda r: r['runs']['c0'][0].update(objects=10 ** 6, completed=False),
       'more objects than the 4'),
      (lambda r: r['runs']['c0'][1].update(grasp_successes=0, grasp_attempts=0, picked=1),
       'picked 1 objects without a successful grasp'),
      (lambda r: r.update(wall_s=-5), 'wall_s'),
      (lambda r: r.update(wall_s=1e308), 'wall_s'),
      (lambda r: r['settings'].update(max_actions='1'), "settings.max_actions: expected a count"),
      (lambda r: r['settings'].update(runs=True), 'settings.runs: expected a count'),
      (lambda r: r['settings'].pop('runs'), 'settings.runs: missing'),
      (lambda r: r['settings'].update(cases=None), 'settings.cases: missing'),
      (lambda r: r['settings'].update(cases=[0]), 'settings.cases'),
      (lambda r: r['settings'].update(protocol='bogus'), "settings.protocol 'bogus': one of "
                                                         'frozen, online, no-repeat'),
      (lambda r: r['settings'].update(protocol=['online']), 'settings.protocol'),
  ]
  for i, (edit, says) in enumerate([(lambda r: None, None)] + tampered):
    data = copy.deepcopy(good)
    edit(data['ordered']['mvcoba'])
    folder = tmp_path / f'e{i}'
    folder.mkdir()
    (folder / 'results.json').write_text(json.dumps(data))
    code = eval_cli.main(['--tables', str(folder), '--out', str(tmp_path / f'o{i}')])
    err = capsys.readouterr().err
    if says is None:
      assert code == 0, err
    else:
      assert code == 2 and says in err and err.count('\n') == 1, (says, err)


def test_a_bar_in_a_case_name_stays_inside_its_cell(tmp_path):
  """Case and row names go into Markdown cells escaped: a '|' does not add a column."""
  from mvcoba_jax.evaluation import report
  data = copy.deepcopy(VALID)
  row = data['ordered']['mvcoba']
  row['runs'] = {'a|b': row['runs']['c0']}
  rescored = {'mvcoba|x': report.rescored(row, 'r')}
  text = report.table(rescored, 'grasp_success', 'grasp success', ['a|b'])
  head, rule, line = text.splitlines()
  assert head.count(' | ') == line.count(' | ') == 2 and 'a\\|b' in head and 'mvcoba\\|x' in line


def test_a_suite_name_of_more_than_one_line_is_refused(tmp_path, capsys):
  """A suite or row name heads a Markdown table: one with a line break (a results.json key, or a
  --suite path) is refused in one line instead of starting a heading of its own."""
  for name in ('ordered\n# injected', 'tab\there'):
    folder = tmp_path / f'r{len(name)}'
    folder.mkdir()
    (folder / 'results.json').write_text(json.dumps({name: VALID['ordered']}))
    assert eval_cli.main(['--tables', str(folder), '--out', str(tmp_path / 'o')]) == 2
    err = capsys.readouterr().err
    assert 'names of one line of text expected' in err and err.count('\n') == 1, err
  assert eval_cli.main(['--baseline', 'heuristic', '--suite', 'a\nb', '--out',
                        str(tmp_path / 'e')]) == 2
  err = capsys.readouterr().err
  assert 'without line breaks or control characters' in err and err.count('\n') == 1, err
