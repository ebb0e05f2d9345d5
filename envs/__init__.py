"""MJX tabletop scenes: objects, gripper, primitives, cameras and scenarios."""
import contextlib
import sys

import threadpoolctl

# Without NVIDIA Warp, importing mujoco.mjx prints "Failed to import warp" on stdout; send it to
# stderr so that stdout stays what our scripts print (the benchmarks' JSON).
with contextlib.redirect_stdout(sys.stderr):
  from mujoco import mjx  # noqa: F401

# MJX's Newton solver and implicit integrator factor nv x nv matrices with LAPACK from scipy's
# OpenBLAS (loaded by the import above). From nv = 256 on, OpenBLAS splits a factorization across
# its own threads, which fight XLA's for the cores: on 2 cores a 288-dof Cholesky took 240 ms
# with them and 0.4 ms without, and a scripted grasp in the random suite's 47-slot scene took
# 23 times longer (benchmarks/suite_scenes.py).
# XLA already parallelises; keep BLAS serial (threadpoolctl also works after the library loaded).
threadpoolctl.threadpool_limits(limits=1, user_api='blas')
