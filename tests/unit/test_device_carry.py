"""What a device call carries stays under its limit: the tracked tree and the wheels that
benchmarks/device.sh installs there (the run of the script itself: tests/sim/test_device_script.py)."""
import pathlib
import subprocess

ROOT = pathlib.Path(__file__).resolve().parents[2]
# mujoco 4.0.1, mujoco-core 4.0.1 (cp312, manylinux_2_28), mujoco-mjx 3.17.0 and trimesh 5.2.0,
# as `pip download` gave them on 2026-12-06 (the command in benchmarks/device.sh).
WHEEL_BYTES = 108_623 + 9_684_944 + 7_257_088 + 751_459
CARRY_LIMIT = 60 * 2 ** 20  # the device call's 64 MiB, less a margin


def test_what_a_device_call_carries_stays_under_60_mib():
  files = subprocess.run(['git', 'ls-files', '-z'], cwd=ROOT, capture_output=True,
                         check=True).stdout.decode().split('\0')
  tracked = sum((ROOT / f).stat().st_size for f in files if f and (ROOT / f).is_file())
  assert tracked + WHEEL_BYTES < CARRY_LIMIT, (tracked, WHEEL_BYTES)
  ignored = (ROOT / '.gitignore').read_text().split()
  assert '.wheels/' in ignored and 'device-out/' in ignored  # carried by name, never committed
