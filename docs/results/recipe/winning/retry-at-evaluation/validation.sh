#!/usr/bin/env bash
# The retry rule on the combination's five claim networks, at evaluation only: each RETRIES given
# (0 1, then 2), val-heaps and val-ordered, 3 runs per case, frozen. (Run at 46d6322 and
# 40d900a through a script that lifted mvcoba-eval's refusal of the field, which it now allows.)
#   bash validation.sh RETRIES...
cd /work/main
export PATH=/work/main/.venv/bin:$PATH PYTHONPATH=/work/main
V=docs/results/validation
echo "start $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD)" >> /work/retry-eval/runs.txt
for r in "$@"; do
  mvcoba-eval --checkpoint /work/study-winning/suppress_push_fill/mvcoba-s{0,1,2,3,4} \
    --suite $V/val-heaps $V/val-ordered --runs 3 --set perception.failed_grasp_retries=$r \
    --out /work/retry-eval/retries-$r --resume > /work/retry-eval/retries-$r.log 2>&1
  echo "retries $r rc $? $(date -u +%FT%TZ)" >> /work/retry-eval/runs.txt
done
