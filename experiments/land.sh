#!/usr/bin/env bash
# Copies a study's finished evaluations (eval/NAME, and eval-online/NAME of its --protocol online
# runs) and its log into docs/results/recipe/STAGE (screen by default; the layout recipe_table.py
# reads: eval/NAME/results.json, study.jsonl) and writes its table beside them (and for the
# per-method screen, `baselines`, each method's chosen preset in choice.md). The log joins the one
# landed before (a study resumed in another sitting with --landed writes a new one), each entry
# once.
#   bash experiments/land.sh /work/study-recipe [screen|confirm|baselines|batch]
set -euo pipefail
cd "$(dirname "$0")/.."
study=$1 screen=docs/results/recipe/${2:-screen}
mkdir -p "$screen/eval"
for d in "$study"/eval*/*/; do  # eval/ (frozen) and eval-online/
  [ -f "$d/done" ] || continue
  to="$screen/$(basename "$(dirname "$d")")/$(basename "$d")"
  mkdir -p "$to"
  cp "$d/results.json" "$d/results.md" "$d/done" "$to/"
done
touch "$screen/study.jsonl"
cat "$screen/study.jsonl" "$study/study.jsonl" | awk '!seen[$0]++' > "$screen/.study.jsonl"
mv "$screen/.study.jsonl" "$screen/study.jsonl"
python experiments/recipe_table.py --workdir "$screen" > "$screen/table.md"
if [ "${2:-}" = baselines ]; then  # the per-method screen: each method's preset, once screened
  python experiments/recipe_table.py --workdir "$screen" --choose > "$screen/choice.md"
fi
