"""The end of `mvcoba-train`: a short table a user reads and the commands that come next."""
from mvcoba_jax.learner.train import closing_report


def test_the_closing_report_says_what_was_learned_and_what_to_run_next():
  trained = {'actions': 6016, 'grasp_attempts': 5451, 'grasp_successes': 4891,
             'grasp_success': 4891 / 5451, 'grasps_per_action': 0.81, 'pushes': 565}
  greedy = {'actions': 32, 'grasp_attempts': 0, 'grasp_successes': 0, 'grasp_success': 0.0,
            'grasps_per_action': 0.0, 'pushes': 32}
  text = closing_report(trained, greedy, 577.0, 'runs/train', 'runs/train/curves.png')
  assert text.splitlines() == [
      'trained 6016 actions in 577 s (10.4 actions/s)',
      '  training  grasp success 89.7 % (4891 of 5451), 565 pushes',
      '  greedy    no grasps, 32 pushes, 32 actions on random drops',
      '  curves    runs/train/curves.png',
      'next:',
      '  mvcoba-eval --checkpoint runs/train --suite dev-random dev-ordered dev-occluded --runs 5',
      '  mvcoba-export --checkpoint runs/train --out runs/train/export']
