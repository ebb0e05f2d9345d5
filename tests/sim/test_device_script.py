"""benchmarks/device.sh at tiny sizes on this CPU: every step a device call takes (the import
check, a physics row with MJX, a training row), so that it cannot fail on the device for a reason
a CPU shows."""
import json
import os
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_the_device_script_runs_every_row_at_tiny_sizes(tmp_path):
  # The script's `python` is this interpreter's, however pytest was started (a venv not activated).
  path = f'{pathlib.Path(sys.executable).parent}{os.pathsep}{os.environ.get("PATH", "")}'
  env = {**os.environ, 'PATH': path, 'OUT': str(tmp_path), 'WHEELS': str(tmp_path / 'no-wheels')}
  done = subprocess.run(['bash', str(ROOT / 'benchmarks' / 'device.sh'), '--tiny'], env=env,
                        capture_output=True, text=True, timeout=1500)
  assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
  devices = json.loads((tmp_path / 'devices.json').read_text())
  assert devices['backend'] == 'cpu' and devices['mujoco']
  rows = (tmp_path / 'rows.txt').read_text().splitlines()
  assert [r.split()[0] for r in rows] == ['physics-b1', 'train-b2'], rows
  assert all(' rc 0 ' in r for r in rows), rows
  physics = json.loads((tmp_path / 'physics-b1.json').read_text())
  assert {'native', 'mjx'} <= {k for r in physics['results'] for k in r}, physics['results']
  train = json.loads((tmp_path / 'train-b2.json').read_text())
  assert train['results'], train
  assert "pip install -e '.[gpu]'" in done.stdout
