#!/usr/bin/env bash
# Lands an mvcoba-reproduce as its protocols finish: the tables of each finished protocol (its
# comparison.md written) into docs/results/reproduction (with online/difference.md, each
# network's online scores less its frozen ones: experiments/protocol_difference.py), the tables
# of an earlier training into docs/results/archive/reproduction-COMMIT (the commit that landed
# them), and seed 0 of every method but MV-COBA exported to pretrained/METHOD with its figures
# under each landed protocol and the commit that trained it (params.npz and model.json: the ONNX
# graph is one mvcoba-export away; pretrained/mvcoba is what `mvcoba-train` gives, landed by
# land_pretrained.sh). Run it again when the online protocol finishes: the same training's
# tables are refreshed in place, and the page of its suites so far is removed.
#   bash experiments/land_reproduction.sh WORKDIR TABLES TRAINED_AT_COMMIT
set -euo pipefail
cd "$(dirname "$0")/.."
workdir=$1 tables=$2 commit=$3 dest=docs/results/reproduction
[ -f "$tables/comparison.md" ] || {
  echo "$tables: no comparison.md: the reproduction's frozen protocol has not finished" >&2; exit 2; }
if [ "$(cat "$dest/trained-at" 2>/dev/null)" != "$commit" ]; then
  old=$(git log -1 --format=%h -- "$dest/comparison.md")
  git mv "$dest" "docs/results/archive/reproduction-$old"
  mkdir -p "$dest"
fi
find "$tables" -maxdepth 1 -type f ! -name '.*' -exec cp {} "$dest"/ \;
results=("$dest/results.json")
if [ -f "$tables/online/comparison.md" ]; then
  mkdir -p "$dest/online" && cp "$tables"/online/* "$dest/online/"
  python experiments/protocol_difference.py "$dest" > "$dest/online/difference.md"
  git rm -q --ignore-unmatch docs/results/reproduction-online-partial.md  # its suites, landed whole
  results+=("$dest/online/results.json")
fi
echo "$commit" > "$dest/trained-at"
for run in "$workdir"/*-s0; do
  method=$(basename "$run" -s0)
  [ "$method" = mvcoba ] && continue
  rm -rf "pretrained/$method"
  mvcoba-export --checkpoint "$run" --out "pretrained/$method" --commit "$commit" \
    --results "${results[@]}"
  rm "pretrained/$method/model.onnx"
done
