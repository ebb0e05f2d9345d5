#!/usr/bin/env bash
# Issue 81, per object: the shipped default evaluated again on `novel` as objects.md evaluated it
# (5 runs per case, frozen, cap 60), by code that counts grasps, picks and pushes per shape
# (691920b); resumable.
set -euo pipefail
cd /work/tree-novel-shapes  # a worktree at 691920b
export PYTHONPATH=$PWD PATH=/work/main/.venv/bin:$PATH MVCOBA_JAX_CACHE=/work/main/.cache/jax
mvcoba-eval --checkpoint pretrained/mvcoba --suite novel --runs 5 --out /work/novel-shapes/eval \
  --resume
