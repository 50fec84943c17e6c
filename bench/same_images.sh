#!/usr/bin/env bash
# Do two ferry binaries render the same images, byte for byte? For
# refactors that must not change behaviour (docs/architecture.md): the
# Cornell box, the island at 1, 3 and 8 ranks (both exchanges), the Stanford
# bunny, pbrt's breakfast room with its lamps, and a part directory.
#   bash bench/same_images.sh OLD_FERRY NEW_FERRY
# Prints one line per case and "same_images: N of M identical"; exits 1 on
# any difference. Takes a few minutes on 2 cores.
set -euo pipefail
old=$1
new=$2
here=$(cd "$(dirname "$0")/.." && pwd)
scenes=$here/../shared/scenes
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mpi=(mpirun --oversubscribe --bind-to none)
[[ $(id -u) == 0 ]] && mpi+=(--allow-run-as-root)
same=0
total=0

# case NAME RANKS ARGS...: renders with both binaries, compares the PFMs.
case_() {
  local name=$1 ranks=$2
  shift 2
  for which in old new; do
    local bin=$old
    [[ $which == new ]] && bin=$new
    if ((ranks == 1)); then
      "$bin" render "$@" -q -o "$work/$name-$which.pfm"
    else
      "${mpi[@]}" -np "$ranks" "$bin" render "$@" -q -o "$work/$name-$which.pfm"
    fi
  done
  total=$((total + 1))
  if cmp -s "$work/$name-old.pfm" "$work/$name-new.pfm"; then
    same=$((same + 1))
    echo "  $name: identical"
  else
    echo "  $name: DIFFERENT"
  fi
}

island=(builtin:island --size 160x90 --spp 2 --threads 1)
case_ cornell 1 builtin:cornell --size 128x128 --spp 8
case_ island-1 1 "${island[@]}"
case_ island-3 3 "${island[@]}"
case_ island-8 8 "${island[@]}"
case_ island-8-bulk 8 "${island[@]}" --exchange bulk
case_ island-3-ray-guided 3 "${island[@]}" --partitioner ray-guided --ray-paths 2000
case_ bunny 1 "$scenes/stanford-bunny/bun_zipper.ply" --size 128x128 --spp 8
case_ breakfast-lamps 1 "$scenes/breakfast/breakfast-lamps.pbrt" --size 120x76 --spp 4
# A part directory each binary makes: the same files, the same image.
for which in old new; do
  bin=$old
  [[ $which == new ]] && bin=$new
  "$bin" partition builtin:island --ranks 3 -o "$work/parts-$which" -q
  "${mpi[@]}" -np 3 "$bin" render "$work/parts-$which" --size 160x90 --spp 2 --threads 1 -q \
    -o "$work/parts-$which.pfm"
done
total=$((total + 2))
# Timings in the manifest differ from run to run; everything else must not.
for which in old new; do
  python3 -c 'import json, sys
def strip(v):
    if isinstance(v, dict): return {k: strip(x) for k, x in v.items() if "seconds" not in k}
    if isinstance(v, list): return [strip(x) for x in v]
    return v
m = json.load(open(sys.argv[1]))
json.dump(strip(m), open(sys.argv[1], "w"), indent=1, sort_keys=True)' "$work/parts-$which/manifest.json"
done
if diff -rq "$work/parts-old" "$work/parts-new" >/dev/null; then
  same=$((same + 1))
  echo "  island part directory: identical files"
else
  echo "  island part directory: DIFFERENT files"
  { diff -rq "$work/parts-old" "$work/parts-new" || true; } | head -5 | sed 's/^/    /'
  echo "    (expected when the part format changed: docs/partitioning.md lists its versions)"
fi
if cmp -s "$work/parts-old.pfm" "$work/parts-new.pfm"; then
  same=$((same + 1))
  echo "  island-parts-3: identical"
else
  echo "  island-parts-3: DIFFERENT"
fi
echo "same_images: $same of $total identical"
((same == total))
