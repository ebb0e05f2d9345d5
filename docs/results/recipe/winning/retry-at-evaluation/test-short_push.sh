#!/usr/bin/env bash
# The retry rule at evaluation on short_push's five claim networks (the default recipe at 3000
# actions), on the test suites with the claim's runs and cap, frozen.
cd /work/main
export PATH=/work/main/.venv/bin:$PATH PYTHONPATH=/work/main
echo "start $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD)" >> /work/retry-short/runs.txt
mvcoba-eval --checkpoint /work/study-winning/short_push/mvcoba-s{0,1,2,3,4} \
  --suite random ordered occluded vpg --runs 5 --set perception.failed_grasp_retries=1 \
  --out /work/retry-short/test-retries-1 --resume > /work/retry-short/test-retries-1.log 2>&1
echo "rc $? $(date -u +%FT%TZ)" >> /work/retry-short/runs.txt
