#!/usr/bin/env bash
# The retry rule at evaluation on the combination's five claim networks, on the test suites with
# the claim's runs and cap (random ordered occluded vpg, 5 runs per case, 60 actions), frozen.
# (Run at 97f4c3c through a script that lifted mvcoba-eval's refusal of the field.)
cd /work/main
export PATH=/work/main/.venv/bin:$PATH PYTHONPATH=/work/main
echo "test start $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD)" >> /work/retry-eval/runs.txt
mvcoba-eval --checkpoint /work/study-winning/suppress_push_fill/mvcoba-s{0,1,2,3,4} \
  --suite random ordered occluded vpg --runs 5 --set perception.failed_grasp_retries=1 \
  --out /work/retry-eval/test-retries-1 --resume > /work/retry-eval/test-retries-1.log 2>&1
echo "test retries 1 rc $? $(date -u +%FT%TZ)" >> /work/retry-eval/runs.txt
