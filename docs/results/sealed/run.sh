#!/usr/bin/env bash
# Issue 80's claim on the sealed suites, run once: the default preset (6000 actions) and the
# reproduction's six methods (each on its screened recipe, `reproduction.RECIPES`, the paper's 3000
# actions) at 5 training seeds no screen used (30-34), then every policy at once on the sealed
# suites and VPG's cases, frozen, 5 runs per case, cap 60. Each step resumes where a killed one
# stopped (training from its checkpoints, the evaluation keeping its finished rows).
set -euo pipefail
cd /work/tree-claim  # a worktree at the commit the claim names (088a9e1)
export PYTHONPATH=$PWD PATH=/work/main/.venv/bin:$PATH MVCOBA_JAX_CACHE=/work/main/.cache/jax
W=/work/claim-80
SEEDS="30 31 32 33 34"
mkdir -p $W
resume() { [ -d "$1" ] && echo --resume || true; }  # a sweep started is continued
mvcoba-train --config default --methods mvcoba --seeds $SEEDS --workdir $W/default $(resume $W/default)
mvcoba-train --config reproduction --set train.total_actions=3000 \
  --methods mvcoba grasp_only mvp cpg --seeds $SEEDS --workdir $W/reproduction $(resume $W/reproduction)
mvcoba-train --config authors --set train.total_actions=3000 \
  --methods mvcoba_2fcn vpg --seeds $SEEDS --workdir $W/authors $(resume $W/authors)
mvcoba-eval --checkpoint $W/default/mvcoba-s* $W/reproduction/*-s* $W/authors/*-s* \
  --suite random ordered packed-ring packed-t_shape packed-stack occluded vpg \
  --runs 5 --max-actions 60 --out $W/eval --resume
