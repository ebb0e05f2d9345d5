#!/usr/bin/env bash
# Issue 82, per shape: the RG2's and the Robotiq 2F-85's policies of seed 20 (issue 80's
# `cut_default` and the gripper study's run) evaluated again as `run.sh` evaluated them (the
# development suites, 3 runs per case, frozen, cap 60) by code that counts grasps, picks and pushes
# per shape (4337dbe); resumable.
set -euo pipefail
cd /work/tree-shapes  # a worktree at 4337dbe
export PYTHONPATH=$PWD PATH=/work/main/.venv/bin:$PATH MVCOBA_JAX_CACHE=/work/main/.cache/jax
W=/work/shapes-82
mvcoba-eval --checkpoint /work/study-80/cut_default/mvcoba-s20 \
  /work/study-82/gripper_robotiq_2f85/mvcoba-s20 \
  --suite dev-random dev-ordered dev-occluded --runs 3 --out $W/eval --resume
