#!/usr/bin/env bash
# The retry rule at evaluation on a claimed variant's five networks (trained without it), on the
# test suites with the claim's runs and cap (random ordered occluded vpg, 5 runs per case, 60
# actions), frozen: suppress_push_fill into /work/retry-eval (run at 97f4c3c, through a script that
# lifted mvcoba-eval's refusal of the field), short_push into /work/retry-short (694b72b).
#   bash test.sh VARIANT WORK
variant=$1 work=$2
cd /work/main
export PATH=/work/main/.venv/bin:$PATH PYTHONPATH=/work/main
echo "test start $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD)" >> $work/runs.txt
mvcoba-eval --checkpoint /work/study-winning/$variant/mvcoba-s{0,1,2,3,4} \
  --suite random ordered occluded vpg --runs 5 --set perception.failed_grasp_retries=1 \
  --out $work/test-retries-1 --resume > $work/test-retries-1.log 2>&1
echo "test retries 1 rc $? $(date -u +%FT%TZ)" >> $work/runs.txt
