"""Issue 69: training at B tabletops as mvcoba-train runs it, in one of the iteration's forms:
`written` (one program of the K steps written out), `per_step` (the one-step program called K
times: `Trainer.compiled` on MJX on a CPU) or `donate` (the same, the state donated to each
call). Times `Trainer.init`'s first call, the iteration's first call (compile and K steps; the
persistent cache only skips XLA's compile, not tracing) and REPS steady calls; prints JSON.

  python docs/results/mjx-compile/per_step.py mjx 8 5 written|per_step|donate
  python docs/results/mjx-compile/per_step.py native 8 4 written|per_step|donate
"""
import functools, json, sys, time
import jax, jax.numpy as jnp
from mvcoba_jax import runtime
runtime.setup()
from mvcoba_jax.config import resolve
from mvcoba_jax.learner import training
from mvcoba_jax.learner.training import Trainer
backend, b, reps, form = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
config = resolve('default', [f'num_envs={b}', f'scene.backend={backend}'])
trainer = Trainer(config)
t = time.perf_counter(); state = jax.block_until_ready(jax.jit(trainer.init)(jax.random.PRNGKey(0))); init_s = time.perf_counter() - t
if form == 'donate':  # `Trainer.compiled`'s one-step form, the state donated to each call
  it = functools.partial(training._one_after_another, jax.jit(trainer.step, donate_argnums=0),
                         config.train.steps_per_iteration)
else:
  it = trainer.compiled(per_step=form == 'per_step')
args = (jnp.bool_(True), jnp.float32(-1.0))
t = time.perf_counter(); state, _ = jax.block_until_ready(it(state, *args)); first = time.perf_counter() - t
walls = []
for _ in range(reps):
  t = time.perf_counter(); state, _ = jax.block_until_ready(it(state, *args)); walls.append(time.perf_counter() - t)
k = config.train.steps_per_iteration
w = sorted(walls)[len(walls) // 2]
print(json.dumps({'backend': backend, 'batch': b, 'form': form, 'steps_per_iteration': k,
  'init_first_call_s': round(init_s, 1), 'iteration_first_call_s': round(first, 1), 'iteration_compile_s': round(first - w, 1),
  'iteration_walls_s': [round(x, 2) for x in walls], 'actions_per_s': round(b * k / w, 3)}), flush=True)
