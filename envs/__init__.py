"""MuJoCo tabletop scenes: objects, gripper, primitives, physics backends, cameras and scenarios."""
import contextlib
import io
import sys

# Without NVIDIA Warp (an optional MJX backend we do not use), importing mujoco.mjx prints "Failed
# to import warp" and "... mujoco_warp" on stdout. Those two lines are dropped; anything else it
# prints goes to stderr, so that stdout stays what our scripts print (the benchmarks' JSON).
with contextlib.redirect_stdout(io.StringIO()) as _printed:
  from mujoco import mjx  # noqa: F401
for _line in _printed.getvalue().splitlines():
  if not _line.startswith(('Failed to import warp:', 'Failed to import mujoco_warp:')):
    print(_line, file=sys.stderr)
