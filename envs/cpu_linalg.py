"""How MJX's linear algebra runs on a CPU: serial BLAS, and one LAPACK call per matrix.

MJX factors nv x nv matrices every step (`cho_factor` and `cho_solve` in the Newton solver, the
mass matrix and the implicitfast integrator), on a CPU through jaxlib's LAPACK kernels and
scipy's OpenBLAS. Two threading problems follow on a 2-core machine; `install()` fixes both. The
MJX backend calls it when it is built on a CPU (the native backend needs neither); it changes the
whole process, once.

- OpenBLAS splits a factorization over its own threads from n = 256 on, which fight XLA's for the
  cores: a 288-dof Cholesky took 240 ms with them and 0.4 ms without, and a scripted grasp in the
  random suite's 47-slot scene 23 times longer (benchmarks/suite_scenes.py). XLA already
  parallelises, so BLAS stays serial (threadpoolctl also works on a library already loaded).
- jaxlib 0.10 splits a batched LAPACK call (a vmapped `cho_factor`) over XLA's intra-op thread
  pool and blocks a pool thread until the pieces finish. When as many such calls run at once as
  the pool has threads (2 here; XLA runs independent calls side by side), every thread waits for
  work that only a waiting thread could run, and the process hangs with the CPU idle. jaxlib
  compiles this path out from 0.11.1, which is not published for this platform. A batched
  Cholesky or triangular solve is therefore lowered as a loop over its matrices, each one
  unbatched LAPACK call that runs on the calling thread. `python benchmarks/batched_lapack.py`
  measures both: hung trials and calls per second, with and without the loop.
"""
import math

import scipy.linalg  # noqa: F401  (loads the OpenBLAS that the limit below applies to)
import threadpoolctl
from jax import lax
from jax._src.interpreters import mlir
from jax._src.lax import linalg as lax_linalg

# The CPU lowerings jaxlib registers for the primitives MJX uses; the loop below falls back to
# them for one matrix at a time.
_LAPACK_LOWERINGS = ((lax_linalg.cholesky_p, lax_linalg._cholesky_cpu_lowering),
                     (lax_linalg.triangular_solve_p, lax_linalg._triangular_solve_cpu_lower))


def _one_matrix_at_a_time(primitive, lapack_lowering):
  """A CPU lowering that runs `primitive` on each matrix of the batch in turn (`lax.map`)."""

  def lower(ctx, *operands, **params):
    if math.prod(ctx.avals_in[0].shape[:-2]) <= 1:
      return lapack_lowering(ctx, *operands, **params)

    def loop(*arrays):
      batch = arrays[0].shape[:-2]
      flat = [a.reshape((-1,) + a.shape[-2:]) for a in arrays]
      out = lax.map(lambda matrices: primitive.bind(*matrices, **params), flat)
      return out.reshape(batch + out.shape[1:])

    return mlir.lower_fun(loop, multiple_results=False)(ctx, *operands)

  return lower


_chosen = False  # install() or use_jaxlib_batched_calls() has set this process up


def install() -> None:
  """Serial BLAS and one LAPACK call per matrix, unless this process already chose."""
  global _chosen
  if _chosen:
    return
  _chosen = True
  threadpoolctl.threadpool_limits(limits=1, user_api='blas')
  for primitive, lapack_lowering in _LAPACK_LOWERINGS:
    mlir.register_lowering(primitive, _one_matrix_at_a_time(primitive, lapack_lowering),
                           platform='cpu')


def use_jaxlib_batched_calls() -> None:
  """jaxlib's batched LAPACK lowerings (they can hang, see above), for good: benchmarks only."""
  global _chosen
  _chosen = True
  for primitive, lapack_lowering in _LAPACK_LOWERINGS:
    mlir.register_lowering(primitive, lapack_lowering, platform='cpu')
