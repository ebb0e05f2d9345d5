#!/usr/bin/env bash
# The policy shipped before the push contract (pretrained/mvcoba at cd9b46a), evaluated with
# pushes cut at the workspace's edge: the same network, suites and evaluation seeds as its landed
# figures (docs/results/pretrained-mvcoba at cd9b46a), so the difference is the contract alone.
cd /work/tree-sealed
export PYTHONPATH=/work/tree-sealed PATH=/work/main/.venv/bin:$PATH MVCOBA_JAX_CACHE=/work/main/.cache/jax
while [ ! -f /work/pre/eval-online/done ]; do sleep 60; done
mvcoba-eval --checkpoint /work/old-shipped/mvcoba --suite dev-random vpg --runs 5 \
  --save-visuals --out /work/old-shipped/eval-cut --resume > /work/old-shipped/eval-cut.log 2>&1 && touch /work/old-shipped/eval-cut/done
