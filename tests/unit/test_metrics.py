"""The evaluation metrics on hand-made run logs, against hand-computed values."""
import math

from mvcoba_jax.evaluation.metrics import RunLog, case_metrics, suite_average


def test_case_metrics_by_hand():
  runs = [RunLog(actions=5, grasp_attempts=4, grasp_successes=4, objects=4, picked=4, lost=0,
                 completed=True),  # one push, four clean grasps
          RunLog(actions=10, grasp_attempts=8, grasp_successes=4, objects=4, picked=4, lost=0,
                 completed=True),
          RunLog(actions=7, grasp_attempts=6, grasp_successes=0, objects=4, picked=0, lost=0,
                 completed=False)]
  m = case_metrics(runs)
  assert m['grasp_success'] == 100.0 * 8 / 18
  assert m['action_efficiency'] == 100.0 * 8 / 15
  assert m['completion'] == 100.0 * 2 / 3
  assert m['objects_picked'] == 100.0 * 8 / 12  # the paper's completion: objects, not runs
  assert m['grasp_to_push'] == 18 / 4
  assert m['runs'] == 3 and m['actions'] == 22
  # The paper's averages (the authors' evaluate.py): each completed run's rate, then the mean.
  assert m['grasp_success_per_run'] == 100.0 * (4 / 4 + 4 / 8) / 2
  assert m['action_efficiency_per_run'] == 100.0 * (4 / 5 + 4 / 10) / 2
  assert math.isnan(m['repeated_failures'])  # not counted in these logs
  counted = [RunLog(5, 4, 4, 4, 4, 0, True, repeated_failures=0),
             RunLog(7, 6, 0, 4, 0, 0, False, repeated_failures=3)]
  assert case_metrics(counted)['repeated_failures'] == 1.5


def test_nothing_completed_and_no_pushes():
  m = case_metrics([RunLog(6, 6, 0, 3, 0, 0, False)])
  assert math.isnan(m['action_efficiency']) and m['completion'] == 0.0
  assert m['objects_picked'] == 0.0
  assert m['grasp_to_push'] == math.inf and m['grasp_success'] == 0.0


def test_suite_average_skips_missing_cells():
  avg = suite_average({'a': {'grasp_success': 50.0, 'action_efficiency': float('nan'),
                             'completion': 0.0, 'objects_picked': 90.0, 'grasp_to_push': 2.0},
                       'b': {'grasp_success': 100.0, 'action_efficiency': 80.0,
                             'completion': 100.0, 'objects_picked': 100.0, 'grasp_to_push': 4.0}})
  assert {k: avg[k] for k in ('grasp_success', 'action_efficiency', 'completion',
                              'objects_picked', 'grasp_to_push')} == {
      'grasp_success': 75.0, 'action_efficiency': 80.0, 'completion': 50.0,
      'objects_picked': 95.0, 'grasp_to_push': 3.0}
