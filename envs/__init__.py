"""MJX tabletop scenes: objects, gripper, primitives, cameras and scenarios."""
import contextlib
import sys

# Without NVIDIA Warp, importing mujoco.mjx prints "Failed to import warp" on stdout; send it to
# stderr so that stdout stays what our scripts print (the benchmarks' JSON).
with contextlib.redirect_stdout(sys.stderr):
  from mujoco import mjx  # noqa: F401

from envs import cpu_linalg  # noqa: E402

cpu_linalg.install()  # serial BLAS, one LAPACK call per matrix: see envs/cpu_linalg.py
