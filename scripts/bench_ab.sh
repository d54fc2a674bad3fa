#!/usr/bin/env bash
# Two builds of `kodawari` side by side on the same benchmarks, interleaved (A, B, A, B,
# ...) so that a noisy, shared machine slows both alike; prints per benchmark, build and
# backend the median, min and max of the runs. For "did this change make it slower".
#
#   bash scripts/bench_ab.sh A_KODAWARI B_KODAWARI [RUNS] [BENCH...]
#
# BENCH is a quoted `kodawari bench` argument list; the default set covers birds, chains,
# the rigged crowd and a viewer frame, at sizes that take about a minute per round on
# two cores.
set -euo pipefail
a="$1"
b="$2"
runs="${3:-3}"
shift $(( $# < 3 ? $# : 3 ))
benches=("$@")
if [[ ${#benches[@]} -eq 0 ]]; then
  benches=(
    "birds --count 1000000 --frames 30"
    "chains --count 100000 --joints 16 --iterations 4 --frames 10"
    "crowd --count 1000 --frames 30"
    "view scenes/crowd-gltf.json --frames 30 --size 640x360"
  )
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
for ((r = 0; r < runs; ++r)); do
  for i in "${!benches[@]}"; do
    for side in A B; do
      bin="$a"
      [[ "$side" == B ]] && bin="$b"
      # shellcheck disable=SC2086
      "$bin" bench ${benches[$i]} --json "$work/$i-$side-$r.json" >/dev/null
    done
  done
done
python3 - "$work" "$runs" "${benches[@]}" <<'EOF'
import json, statistics, sys
work, runs, benches = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
for i, bench in enumerate(benches):
    print(f"bench {bench}  ({runs} runs each, interleaved)")
    rows = {}
    for side in "AB":
        for r in range(runs):
            data = json.load(open(f"{work}/{i}-{side}-{r}.json"))
            for res in data["results"]:
                key = res.get("backend") or res.get("configuration")
                rows.setdefault(key, {}).setdefault(side, []).append(res["per_second"])
    for key, sides in rows.items():
        a, b = sides.get("A", []), sides.get("B", [])
        fmt = lambda v: f"{statistics.median(v):.4g} [{min(v):.4g}, {max(v):.4g}]" if v else "-"
        ratio = statistics.median(b) / statistics.median(a) if a and b else float("nan")
        print(f"  {key:18s} A {fmt(a):34s} B {fmt(b):34s} B/A {ratio:.3f}")
EOF
