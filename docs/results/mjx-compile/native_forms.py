"""Native physics at B tabletops, K=4 (the default preset), in one of the iteration's forms:
`written` (one program of K steps), `loop` (the one-step program, `Trainer.step` jitted, called K
times) or `donate` (the same, the state donated); prints the first call's time, the steady calls'
walls and actions/s as JSON (mjx-compile.md, "One step's program called K times").

  python docs/results/mjx-compile/native_forms.py written|loop|donate native 8 4
"""
import json, sys, time
import jax, jax.numpy as jnp
from mvcoba_jax import runtime
runtime.setup()
from mvcoba_jax.config import resolve
from mvcoba_jax.learner.training import Trainer
form, backend, b, reps = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
config = resolve('default', [f'num_envs={b}', f'scene.backend={backend}'])
trainer = Trainer(config)
state = jax.jit(trainer.init)(jax.random.PRNGKey(0))
jax.block_until_ready(state)
k = config.train.steps_per_iteration
args = (jnp.bool_(True), jnp.float32(-1.0))
if form == 'written':
  f = jax.jit(trainer.iterate)
  it = lambda s: f(s, *args)
else:
  step = jax.jit(trainer.step, donate_argnums=(0,) if form == 'donate' else ())
  def it(s):
    logs = []
    for _ in range(k):
      s, log = step(s, *args); logs.append(log)
    return s, jax.tree.map(lambda *x: jnp.stack(x), *logs)
t = time.perf_counter(); state, _ = jax.block_until_ready(it(state)); first = time.perf_counter() - t
walls = []
for _ in range(reps):
  t = time.perf_counter(); state, log = jax.block_until_ready(it(state)); walls.append(time.perf_counter() - t)
print(json.dumps({'form': form, 'backend': backend, 'batch': b, 'first_s': first, 'walls': walls,
  'actions_per_s': b * k * reps / sum(walls)}), flush=True)
