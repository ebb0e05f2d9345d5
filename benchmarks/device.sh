#!/usr/bin/env bash
# The accelerator measurements in one device call of under 9 minutes (docs/results/gpu-h200.md
# holds the last ones): installs the carried mujoco and mujoco-mjx wheels over the image's JAX,
# checks that JAX sees the GPU, then the physics rows (native on every host thread and MJX, 10
# objects, 64 to 4096 tabletops) and the training rows (native and MJX, 64 and 256 tabletops),
# each under its own time limit so that one slow row cannot sink the rest. Every row writes
# OUT/NAME.json (its benchmark's JSON) and OUT/NAME.err; OUT/rows.txt lists each row's exit
# status and seconds (124: its limit). Warp's rows need `pip install -e '.[gpu]'`, whose
# warp-lang wheel (149 MB) no device call can carry: the script prints the command for a machine
# where that install works.
#
#   pip download --no-deps -d .wheels mujoco==4.0.1 mujoco-core==4.0.1 mujoco-mjx==3.17.0 \
#     trimesh==5.2.0 --python-version 3.12 --platform manylinux_2_28_x86_64 --only-binary :all:
#   # 17.8 MB (WHEEL_BYTES in tests/unit/test_device_script.py); then, on the device, with
#   # .wheels carried:  bash benchmarks/device.sh   (OUT: where the rows go, $OUT there)
#   bash benchmarks/device.sh --tiny   # the same steps at tiny sizes, on any machine
set -u
cd "$(dirname "$0")/.."
OUT=${OUT:-$PWD/device-out}
WHEELS=${WHEELS:-$PWD/.wheels}
mkdir -p "$OUT"
: > "$OUT/rows.txt"
if [ "${1:-}" = --tiny ]; then  # CI: every step, at sizes a 2-core CPU runs in a minute or two
  PHYSICS=(1) MJX_PHYSICS=(1) TRAIN=(2) MJX_TRAIN=() LIMIT_PHYSICS=600 LIMIT_TRAIN=600 REPEATS=1
  OBJECTS=2  # MJX compiles a scene of two boxes in a third of the 10-object scene's time
else
  PHYSICS=(64 256 1024 4096) MJX_PHYSICS=(64 256 1024 4096) TRAIN=(64 256) MJX_TRAIN=(64)
  LIMIT_PHYSICS=60 LIMIT_TRAIN=100 REPEATS=2 OBJECTS=10
fi

# The carried wheels, without their dependencies: the image's JAX (with CUDA) stays. The project
# runs from its tree (PYTHONPATH), not installed: its pinned jax would replace the image's.
if compgen -G "$WHEELS/*.whl" >/dev/null; then
  python -m pip install -q --no-deps "$WHEELS"/*.whl 2>&1 | tail -2
fi
export PYTHONPATH=$PWD${PYTHONPATH:+:$PYTHONPATH}
python - > "$OUT/devices.json" <<'EOF'
import json, sys
try:
  import jax, mujoco
  from mujoco import mjx  # noqa: F401
except ImportError as e:
  print(json.dumps({'error': f'{e}: carry the mujoco and mujoco-mjx wheels in .wheels'}))
  sys.exit(1)
print(json.dumps({'jax': jax.__version__, 'mujoco': mujoco.__version__,
                  'backend': jax.default_backend(), 'devices': [str(d) for d in jax.devices()]}))
EOF
[ $? -eq 0 ] || { cat "$OUT/devices.json"; exit 1; }
cat "$OUT/devices.json"

row() {  # NAME LIMIT_S COMMAND...: one measurement under its own limit
  local name=$1 limit=$2 start=$SECONDS
  shift 2
  timeout "$limit" "$@" > "$OUT/$name.json" 2> "$OUT/$name.err"
  local rc=$?
  echo "$name rc $rc $((SECONDS - start)) s" | tee -a "$OUT/rows.txt"
}
for b in "${PHYSICS[@]}"; do
  mjx=(); [[ " ${MJX_PHYSICS[*]} " == *" $b "* ]] && mjx=("$b")
  row "physics-b$b" "$LIMIT_PHYSICS" python benchmarks/physics.py --objects "$OBJECTS" --batch "$b" \
    --mjx-batch "${mjx[@]}" --repeats "$REPEATS"
done
for b in "${TRAIN[@]}"; do
  mjx=(); [[ " ${MJX_TRAIN[*]} " == *" $b "* ]] && mjx=("$b")
  tiny=(); [ "${1:-}" = --tiny ] && tiny=(--config tiny)
  row "train-b$b" "$LIMIT_TRAIN" python benchmarks/train.py "${tiny[@]}" --batch "$b" \
    --mjx-batch "${mjx[@]}" --targets acting --repeats "$REPEATS"
done
echo "Warp's rows, on a machine where pip install -e '.[gpu]' works:"
echo "  python benchmarks/physics.py --objects 10 --batch 64 256 1024 4096 --mjx-batch --warp-batch 64 256 1024 4096"
echo "  python benchmarks/train.py --config gpu --batch 64 256 --mjx-batch --warp-batch 64 256 --targets acting"
