#!/usr/bin/env bash
# Long renders: a render stopped after frame k (its checkpoint) and resumed to
# frame n gives, bit for bit, the image of an uninterrupted n-frame render, at
# 1 and 3 ranks and across rank counts; a checkpoint of another render is
# refused with a message naming it, and nothing is written; --time-limit
# stops after the frame that crosses it and writes the image of the frames
# done.
set -euo pipefail
ferry=$1
source_dir=$2
source "$source_dir/tests/tools/multirank_test_env.sh"

scene="builtin:cornell"
args=(--size 40x32 --spp 2 --max-depth 4 --seed 5 -q --threads 1)
same() { cmp "$1" "$2" && echo "  $3: identical"; }

"$ferry" render "$scene" "${args[@]}" --frames 6 -o "$work/full.pfm"
# 1 rank: frames 0-2, then 3-5 from the checkpoint (which is then updated).
"$ferry" render "$scene" "${args[@]}" --frames 3 --checkpoint "$work/c1.ckpt" -o "$work/part.pfm"
"$ferry" render "$scene" "${args[@]}" --frames 6 --resume "$work/c1.ckpt" --checkpoint "$work/c1.ckpt" \
  -o "$work/resumed1.pfm"
same "$work/full.pfm" "$work/resumed1.pfm" "1 rank, stopped after 3 of 6 frames and resumed"
# 3 ranks, checkpoints every 2 frames: resume from the one after frame 4.
mpirun_n 3 "$ferry" render "$scene" "${args[@]}" --frames 4 --checkpoint "$work/c3.ckpt" \
  --checkpoint-every 2 -o "$work/part3.pfm"
mpirun_n 3 "$ferry" render "$scene" "${args[@]}" --frames 6 --resume "$work/c3.ckpt" -o "$work/resumed3.pfm"
same "$work/full.pfm" "$work/resumed3.pfm" "3 ranks, stopped after 4 of 6 frames and resumed"
# Any rank count may resume any checkpoint: made on 3 ranks, resumed on 2 (overlapped) and 1.
mpirun_n 2 "$ferry" render "$scene" "${args[@]}" --frames 6 --resume "$work/c3.ckpt" -o "$work/resumed2.pfm"
same "$work/full.pfm" "$work/resumed2.pfm" "made on 3 ranks, resumed on 2"
"$ferry" render "$scene" "${args[@]}" --frames 6 --resume "$work/c3.ckpt" -o "$work/resumed1b.pfm"
same "$work/full.pfm" "$work/resumed1b.pfm" "made on 3 ranks, resumed on 1"

# Refused: another seed, another size, every frame already done, a missing
# or corrupt file. One message, exit 1, the previous output untouched.
echo "good image" > "$work/out.pfm"
refuse() {  # name, fragment, ferry arguments...
  local name=$1 fragment=$2
  shift 2
  if mpirun_n 2 "$ferry" render "$@" -o "$work/out.pfm" 2> "$work/stderr"; then
    echo "FAIL: $name: accepted"; exit 1
  fi
  grep -q -- "$fragment" "$work/stderr" || { echo "FAIL: $name: stderr lacks '$fragment'"; cat "$work/stderr"; exit 1; }
  [ "$(cat "$work/out.pfm")" = "good image" ] || { echo "FAIL: $name: replaced the output"; exit 1; }
  echo "  refused, $name: $(grep -m1 'error' "$work/stderr")"
}
other=(--size 40x32 --spp 2 --max-depth 4 -q --threads 1)
refuse "another seed" "of another render" "$scene" "${other[@]}" --seed 6 --frames 8 --resume "$work/c3.ckpt"
refuse "another size" "of another render" "$scene" --size 40x30 --spp 2 --max-depth 4 --seed 5 -q --frames 8 --resume "$work/c3.ckpt"
refuse "nothing left" "holds 4 frames already" "$scene" "${args[@]}" --frames 4 --resume "$work/c3.ckpt"
refuse "missing" "no such checkpoint" "$scene" "${args[@]}" --frames 8 --resume "$work/none.ckpt"
head -c 100 "$work/c3.ckpt" > "$work/cut.ckpt"
refuse "truncated" "truncated" "$scene" "${args[@]}" --frames 8 --resume "$work/cut.ckpt"

# --time-limit: a render of many frames stops after the frame that crosses
# one second, and writes the image of the frames it did.
start=$SECONDS
mpirun_n 2 "$ferry" render "$scene" --size 64x64 --spp 4 --max-depth 4 -q --threads 1 --frames 100000 \
  --time-limit 1 -o "$work/limited.pfm" --stats "$work/limited.json"
took=$((SECONDS - start))
frames=$(python3 -c "import json,sys; print(len(json.load(open(sys.argv[1]))['render']['frames']))" "$work/limited.json")
[ -s "$work/limited.pfm" ] || { echo "FAIL: --time-limit wrote no image"; exit 1; }
[ "$frames" -ge 1 ] && [ "$frames" -lt 100000 ] || { echo "FAIL: --time-limit rendered $frames frames"; exit 1; }
[ "$took" -lt 30 ] || { echo "FAIL: --time-limit 1 took ${took}s"; exit 1; }
echo "  --time-limit 1: $frames frames, ${took}s in all"
echo "checkpoint_test: all passed"
