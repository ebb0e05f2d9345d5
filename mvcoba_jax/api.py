"""The library calls under the commands: `train` and `sweep` (mvcoba-train), `evaluate` and
`join_evaluations` (mvcoba-eval), and the policy loader. Each is documented where it lives:
training runs in `learner/train.py`, evaluations in `evaluation/session.py` (`EvalSpec`).

    import mvcoba_jax
    from mvcoba_jax.config import resolve
    result = mvcoba_jax.train(resolve('tiny'), 'runs/tiny')
    report = mvcoba_jax.evaluate(['runs/tiny'], ['occluded'], runs=2, out='runs/tiny-eval')
    policy = mvcoba_jax.load_policy('runs/tiny')
    action = policy.act(color, depth, changed=True)  # a deploy.Action, workspace frame
"""
from __future__ import annotations

from mvcoba_jax.config import Error
from mvcoba_jax.evaluation.session import (RESULT_FILES, EvalSpec, EvaluationError, check_work,
                                           join_evaluations)
from mvcoba_jax.evaluation.session import evaluate as evaluate_spec
from mvcoba_jax.learner.train import (RUN_FILES, TrainError, TrainResult, resumable, sweep,
                                      sweep_runs, train)
from mvcoba_jax.policy import Policy
from mvcoba_jax.policy import load as load_policy

__all__ = ['Error', 'EvalSpec', 'EvaluationError', 'Policy', 'RESULT_FILES', 'RUN_FILES',
           'TrainError',
           'TrainResult', 'check_work', 'evaluate', 'join_evaluations', 'load_policy',
           'resumable', 'sweep', 'sweep_runs', 'train']


def evaluate(checkpoints=(), suites=('all',), *, baseline: str | None = None, runs: int = 5,
             max_actions: int = 60, seed: int = 0, protocol: str = 'frozen',
             config: str | None = None, overrides=(), blocks=(), allow_bad_cases: bool = False,
             fit_overlaps: float | None = None, out='eval_out', resume: bool = False,
             overwrite: bool = False,
             save_visuals: bool = False, video: bool = False, progress: bool = True) -> dict:
  """Evaluates trained policies (work directories or exports) and a `baseline` on suites (names
  of `suites.SUITES`, `all`, or paths of case files and folders): every case x `runs` runs of a
  suite in one compiled lockstep loop, each run capped at `max_actions`. `protocol` 'frozen'
  acts greedily with the trained network, 'online' lets every run go on learning from its own
  actions, 'no-repeat' is frozen but never repeats a failed action of its run. `fit_overlaps`
  (a bound in m) moves objects of a case that interpenetrate as the file places them apart
  first (`sim.scenarios.fit_overlaps`), refusing a case where one would move farther.

  Returns the report written to `out` (results.json, results.md, rewritten after each row):
  suite -> row label -> per-case metrics, their means, each run's counts and the settings the
  row was evaluated with. `resume` keeps `out`'s rows of the same settings and evaluates the
  rest; an `out` holding results is refused unless `resume` or `overwrite`. A policy evaluates
  in its own config with `overrides` applied (`config.evaluated`); the baseline in `config`.
  JAX's compiled programs are released after each row (`jax.clear_caches`), the caller's too.
  Raises EvaluationError before anything compiles when an input cannot serve.
  """
  return evaluate_spec(EvalSpec(
      checkpoints=checkpoints, suites=suites, baseline=baseline, runs=runs,
      max_actions=max_actions, seed=seed, protocol=protocol, config=config, overrides=overrides,
      blocks=blocks, allow_bad_cases=allow_bad_cases, fit_overlaps=fit_overlaps, out=out,
      resume=resume, overwrite=overwrite, save_visuals=save_visuals, video=video,
      progress=progress))
