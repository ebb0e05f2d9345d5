"""What loading a trained policy from a training work directory costs: wall time and the
process's peak memory, each load in a fresh process, beside a process that only imports.

`policy.load` reads the network's parameters alone from the checkpoint. Run it with another
checkout on PYTHONPATH to measure that checkout's load the same way. Prints one JSON object.

  python benchmarks/load_policy.py --checkpoint runs/train [--repeats 3]
"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys

PROBE = '''
import resource, sys, time
from mvcoba_jax import runtime
from mvcoba_jax.policy import load
runtime.setup()
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
start = time.perf_counter()
if sys.argv[1] != '-':
  load(sys.argv[1])
print(time.perf_counter() - start, before / 1024, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
'''


def probe(checkpoint: str) -> tuple[float, float, float]:
  out = subprocess.run([sys.executable, '-c', PROBE, checkpoint], capture_output=True,
                       text=True, check=True)
  return tuple(float(v) for v in out.stdout.split()[-3:])


def main():
  parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  parser.add_argument('--checkpoint', required=True)
  parser.add_argument('--repeats', type=int, default=3)
  args = parser.parse_args()
  imported = [probe('-') for _ in range(args.repeats)]
  loaded = [probe(args.checkpoint) for _ in range(args.repeats)]
  import mvcoba_jax  # noqa: PLC0415 (which checkout was measured)
  peak_import = statistics.median(p for _, _, p in imported)
  peak_load = statistics.median(p for _, _, p in loaded)
  json.dump({'benchmark': 'load_policy', 'checkpoint': args.checkpoint,
             'package': mvcoba_jax.__file__, 'repeats': args.repeats,
             'load_s': statistics.median(t for t, _, _ in loaded),
             'peak_rss_mb_import_only': peak_import, 'peak_rss_mb_after_load': peak_load,
             'load_adds_mb': peak_load - peak_import}, sys.stdout, indent=1)
  print()


if __name__ == '__main__':
  main()
