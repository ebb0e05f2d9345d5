#!/usr/bin/env bash
# Lands a finished mvcoba-reproduce: its tables (both protocols) into docs/results/reproduction,
# the tables they replace into docs/results/archive/reproduction-COMMIT (the commit that landed
# them), and seed 0 of every method exported to pretrained/METHOD with its figures under each
# protocol and the commit that trained it (params.npz and model.json: the ONNX graph is one
# mvcoba-export away).
#   bash experiments/land_reproduction.sh WORKDIR TABLES TRAINED_AT_COMMIT
set -euo pipefail
cd "$(dirname "$0")/.."
workdir=$1 tables=$2 commit=$3 dest=docs/results/reproduction
[ -f "$tables/comparison.md" ] && [ -f "$tables/online/comparison.md" ] || {
  echo "$tables: no comparison.md of both protocols: the reproduction has not finished" >&2; exit 2; }
old=$(git log -1 --format=%h -- "$dest/comparison.md")
git mv "$dest" "docs/results/archive/reproduction-$old"
mkdir -p "$dest" && cp -r "$tables"/. "$dest"/
for run in "$workdir"/*-s0; do
  method=$(basename "$run" -s0)
  rm -rf "pretrained/$method"
  mvcoba-export --checkpoint "$run" --out "pretrained/$method" --commit "$commit" \
    --results "$dest/results.json" "$dest/online/results.json"
  rm "pretrained/$method/model.onnx"
done
