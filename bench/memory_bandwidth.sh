#!/usr/bin/env bash
# Rays forwarded against memory per rank (issue 16): each of the paper's six
# partitioners, and ray-guided at several --max-part caps, partition a scene
# for RANKS ranks; the bandwidth predictor (--predict-forwards: every rank a
# thread of one process, the real forwarding operator; within 4 % of the MPI
# counts, docs/evaluation.md) gives forwards per camera path for each named
# view and the "unseen" camera no partitioner saw. Prints, per scene, the
# largest part (as a factor of an even share, total / ranks) and forwards per
# path for every view; writes memory_bandwidth.csv and one plot per scene
# (forwards per path against the largest part) into OUT.
#
#   OUT=docs/images/memory-bandwidth bash bench/memory_bandwidth.sh [FERRY]
#   SCENES="island landscape" RANKS=8 CAPS="1.25 2 3 3.8 4.2 6" (the defaults); SCALE=0.05 a small island
#
# Counts only: deterministic, independent of the machine's load.
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
here=$(cd "$(dirname "$0")" && pwd)
scenes=${SCENES:-island landscape}
ranks=${RANKS:-8}
caps=${CAPS:-1.25 2 3 3.8 4.2 6}
scale=${SCALE:-}  # the builtin scenes' scale (their default when empty)
out=${OUT:-memory-bandwidth}
work=$(mktemp -d -p "${TMPDIR:-/tmp}")
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"
# Debian's python3 has python3-matplotlib; a python3 earlier on PATH (pyenv) may not.
PY=""
for py in /usr/bin/python3 python3; do
  if "$py" -c "import matplotlib" 2>/dev/null; then PY=$py; break; fi
done
[ -n "$PY" ] || { echo "memory_bandwidth: python3-matplotlib is missing (bash scripts/install-deps.sh)" >&2; exit 1; }

# The cameras no partitioner has seen: the same as bench/paper-eval's.
unseen_island="--look-from -600,120,-500 --look-at 0,60,0"
unseen_landscape="--look-from -140,30,140 --look-at 0,5,0"

echo "ferry $(git -C "$here" rev-parse --short HEAD 2>/dev/null), $(nproc) cores; $ranks ranks; ray-guided caps: $caps"
for scene in $scenes; do
  camera_var="unseen_$scene"
  runs=""
  for p in spatial-simple spatial-sah object-naive object-proxies bvh-style best; do runs="$runs $p:"; done
  for cap in $caps; do runs="$runs ray-guided:$cap"; done
  for run in $runs; do
    p=${run%%:*}
    cap=${run#*:}
    flags=()
    [ -n "$cap" ] && flags=(--max-part "$cap")
    dir="$work/$scene-$p-$cap"
    # shellcheck disable=SC2086 # the camera is several flags
    "$ferry" partition "builtin:$scene${scale:+?scale=$scale}" --ranks "$ranks" --partitioner "$p" "${flags[@]}" -o "$dir" -q \
      --predict-forwards ${!camera_var} > "$dir.log" 2>&1 ||
      { tail -5 "$dir.log" >&2; echo "memory_bandwidth: partition $scene $p $cap failed" >&2; exit 1; }
  done
done

"$PY" - "$work" "$out" "$ranks" <<'PY'
import csv, glob, json, os, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

work, out, ranks = sys.argv[1], sys.argv[2], int(sys.argv[3])
rows = []
for manifest in sorted(glob.glob(os.path.join(work, "*", "manifest.json"))):
    scene, rest = os.path.basename(os.path.dirname(manifest)).split("-", 1)
    m = json.load(open(manifest))
    cap = m["options"].get("max_part") if m["partitioner"] == "ray-guided" else None
    largest = max(p["estimated_bytes"] for p in m["parts"])
    share = m["input_bytes"] / ranks
    for pred in m["predictions"]:
        view = "unseen" if pred["view"] == "command line" else pred["view"]
        paths = max(1, pred["camera_paths"])
        rows.append({"scene": scene, "partitioner": m["partitioner"], "max_part": cap,
                     "largest_part": largest / share, "view": view,
                     "forwards_per_path": pred["forwards_per_path"],
                     # Of those, per path: shadow rays, rays sent back only to be
                     # shaded, and rays that found nothing where they were sent.
                     "shadow_per_path": pred["shadow_rays_forwarded"] / paths,
                     "to_shade_per_path": pred["forwarded_to_shade"] / paths,
                     "no_hit_per_path": pred["visits_without_hit"] / paths})
with open(os.path.join(out, "memory_bandwidth.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
    w.writeheader()
    w.writerows(rows)

for scene in sorted({r["scene"] for r in rows}):
    rs = [r for r in rows if r["scene"] == scene]
    views = list(dict.fromkeys(r["view"] for r in rs))
    configs = sorted(dict.fromkeys((r["partitioner"], r["max_part"]) for r in rs),
                     key=lambda c: (c[0], c[1] or 0))
    label = lambda c: c[0] if c[1] is None else f"ray-guided {c[1]:g}"
    print(f"\n{scene}: largest part (x an even share), forwards per camera path")
    print(f"  {'partitioner':<18} {'largest':>8} " + " ".join(f"{v:>9}" for v in views))
    for c in configs:
        cr = {r["view"]: r for r in rs if (r["partitioner"], r["max_part"]) == c}
        print(f"  {label(c):<18} {cr[views[0]]['largest_part']:>7.2f}x " +
              " ".join(f"{cr[v]['forwards_per_path']:>9.3f}" for v in views))
    fig, axes = plt.subplots(1, len(views), figsize=(3.2 * len(views), 3.5), sharey=False)
    for ax, view in zip(axes, views):
        vr = [r for r in rs if r["view"] == view]
        rg = sorted((r for r in vr if r["partitioner"] == "ray-guided"), key=lambda r: r["max_part"])
        ax.plot([r["largest_part"] for r in rg], [r["forwards_per_path"] for r in rg], "o-",
                color="black", label="ray-guided, --max-part 1.25..")
        for r in vr:
            if r["partitioner"] == "ray-guided":
                continue
            ax.plot(r["largest_part"], r["forwards_per_path"], "s", label=r["partitioner"])
        ax.set_title(f"{scene}: {view}", fontsize=9)
        ax.set_xlabel("largest part / even share", fontsize=8)
        ax.set_yscale("log")
        ax.tick_params(labelsize=7)
    axes[0].set_ylabel("forwards per camera path", fontsize=8)
    # One legend below the panels, where it covers no point.
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    fig.savefig(os.path.join(out, f"memory-bandwidth-{scene}.png"), dpi=110)

# At equal memory: each of the six against ray-guided at the largest cap
# whose largest part is no larger than that partitioner's (3 % tolerance, so
# that `best`'s 1.23-1.25x meets ray-guided's 1.26x at --max-part 1.25).
six = list(dict.fromkeys(r["partitioner"] for r in rows if r["partitioner"] != "ray-guided"))
wins = pairs = 0
print("\nat equal memory: ray-guided (largest cap within the partitioner's largest part) against each")
for scene in sorted({r["scene"] for r in rows}):
    rs = [r for r in rows if r["scene"] == scene]
    for p in six:
        for view in dict.fromkeys(r["view"] for r in rs):
            pr = next(r for r in rs if r["partitioner"] == p and r["view"] == view)
            rg = [r for r in rs if r["partitioner"] == "ray-guided" and r["view"] == view]
            fits = [r for r in rg if r["largest_part"] <= 1.03 * pr["largest_part"]]
            c = max(fits, key=lambda r: (r["largest_part"], -r["max_part"])) if fits else \
                min(rg, key=lambda r: r["largest_part"])
            win = c["forwards_per_path"] < pr["forwards_per_path"]
            pairs += 1
            wins += win
            print(f"  {scene:<10} {view:<9} {p:<15} {pr['largest_part']:5.2f}x {pr['forwards_per_path']:7.3f}"
                  f"   ray-guided {c['max_part']:g}: {c['largest_part']:5.2f}x {c['forwards_per_path']:7.3f}"
                  f"{'  fewer' if win else ''}")
print(f"ray-guided forwards fewer on {wins} of {pairs} partitioner x view pairs")
print(f"\nwrote {out}/memory_bandwidth.csv and memory-bandwidth-*.png")
PY
