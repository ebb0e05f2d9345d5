#!/usr/bin/env bash
# Issue 80's heap losses and MuJoCo's noslip pass: the creep of settled heaps left alone, the
# shipped policy evaluated frozen with the pass (against its landed figures without it), then the
# 2-seed screen of training with it against issue 80's `cut_default` at seeds 20-21, validation
# suites only; resumable.
set -euo pipefail
cd /work/tree-noslip  # a worktree at 1caf328, the commit that added scene.noslip_iterations
export PYTHONPATH=$PWD PATH=/work/main/.venv/bin:$PATH MVCOBA_JAX_CACHE=/work/main/.cache/jax
W=/work/noslip
python benchmarks/heap_creep.py --noslip 0 3 10 --seconds 20 > $W/creep.json
mvcoba-eval --checkpoint pretrained/mvcoba --suite dev-random vpg --runs 5 \
  --set scene.noslip_iterations=3 --out $W/eval-ns3 --save-visuals --resume
python experiments/recipe_study.py --workdir /work/study-80 --variants cut_default noslip \
  --seeds 20 21 --runs 3 --suites docs/results/validation/val-packed \
  docs/results/validation/val-heaps docs/results/validation/val-occluded-high
