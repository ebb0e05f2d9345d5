"""MJX's linear algebra on a CPU: serial BLAS and one LAPACK call per matrix (envs/cpu_linalg.py)."""
import os
import pathlib
import re
import subprocess
import sys

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import scipy
import threadpoolctl
from mujoco import mjx

from envs import cpu_linalg

cpu_linalg.install()  # what the MJX backend does when it is built on a CPU

BOX_ON_FLOOR = """
<mujoco>
  <option solver="Newton" jacobian="sparse" integrator="implicitfast"/>
  <worldbody>
    <geom type="plane" size="1 1 0.1"/>
    <body pos="0 0 0.05"><freejoint/><geom type="box" size="0.02 0.02 0.02"/></body>
    <body pos="0.1 0 0.05"><freejoint/><geom type="box" size="0.02 0.02 0.02"/></body>
  </worldbody>
</mujoco>
"""


def lapack_batch_dims(fn, *args) -> list[int]:
  """`num_batch_dims` of every LAPACK call in the program that `fn` lowers to on the CPU."""
  text = jax.jit(fn).lower(*args).as_text()
  calls = re.findall(r'custom_call @lapack_\w+\(.*?num_batch_dims = "(\d+)"', text)
  return [int(n) for n in calls]


def test_scipy_blas_is_serial_once_installed():
  """From nv = 256 (the random suite's scene) OpenBLAS's own threads fight XLA's and a grasp takes
  23 times longer. Other BLAS copies (OpenCV bundles one) play no part in the physics."""
  scipy_libs = pathlib.Path(scipy.__file__).parent.parent / 'scipy.libs'
  blas = [lib for lib in threadpoolctl.threadpool_info()
          if pathlib.Path(lib['filepath']).parent == scipy_libs]
  assert blas, f'scipy\'s BLAS not found loaded from {scipy_libs}'
  assert all(lib['num_threads'] == 1 for lib in blas), blas


def test_batched_cholesky_and_solve_are_right_and_run_one_matrix_per_lapack_call():
  """A batched LAPACK call blocks an XLA pool thread on work queued to the same pool, and two at
  once hang a 2-core machine (benchmarks/batched_lapack.py); each call must hold one matrix."""
  m = np.random.default_rng(0).normal(size=(3, 6, 6))
  spd = (m @ m.transpose(0, 2, 1) + 6 * np.eye(6)).astype(np.float32)
  b = np.ones((3, 6), np.float32)

  def factor_and_solve(a, rhs):
    factor = jax.scipy.linalg.cho_factor(a, lower=True)
    return factor[0], jax.scipy.linalg.cho_solve(factor, rhs)

  batched = jax.vmap(factor_and_solve)
  dims = lapack_batch_dims(batched, spd, b)
  assert len(dims) == 3 and dims == [0, 0, 0], dims  # potrf, then trsm twice
  lower, x = jax.jit(batched)(spd, b)
  np.testing.assert_allclose(np.tril(lower), np.linalg.cholesky(spd), rtol=1e-5, atol=1e-5)
  np.testing.assert_allclose(x, np.linalg.solve(spd, b[..., None])[..., 0], rtol=1e-4, atol=1e-5)


def test_vmapped_mjx_step_makes_no_batched_lapack_call():
  """What the training and evaluation step compiles to: MJX's own factorizations, vmapped."""
  model = mjx.put_model(mujoco.MjModel.from_xml_string(BOX_ON_FLOOR))
  data = jax.vmap(lambda _: mjx.make_data(model))(jnp.arange(4))
  dims = lapack_batch_dims(jax.vmap(mjx.step, in_axes=(None, 0)), model, data)
  assert dims, 'no LAPACK call found: has MJX stopped factoring on the CPU?'
  assert set(dims) == {0}, dims


def test_importing_envs_leaves_the_process_as_it_was():
  """Only building the MJX backend on a CPU installs these settings; importing does not."""
  code = ('import re, jax, numpy as np, envs.tabletop\n'
          'a = np.tile(np.eye(3, dtype=np.float32), (2, 1, 1))\n'
          'text = jax.jit(jax.vmap(jax.numpy.linalg.cholesky)).lower(a).as_text()\n'
          'print(re.findall(r\'custom_call @lapack_\\w+\\(.*?num_batch_dims = "(\\d+)"\', text))\n')
  root = pathlib.Path(__file__).resolve().parent.parent
  out = subprocess.run([sys.executable, '-c', code], cwd=root, capture_output=True, text=True,
                       env=dict(os.environ, PYTHONPATH=str(root)), timeout=300)
  assert out.returncode == 0, out.stderr[-2000:]
  assert out.stdout.strip() == "['1']", out.stdout  # jaxlib's own batched call, not the loop
