#!/usr/bin/env bash
# The sweep's throughput (issue 20, part 4): one realistic short study -- Net A's first half
# second of flight (scenarios/net_a_0.5.yaml, 11 x 11 knots, 880 segments), the drag
# coefficient x the corner mass on a 3 x 3 grid -- run by `netlab sweep` with 1 and 2 threads
# and, when netlab is built with MPI and mpirun is there, by 2 MPI ranks of 1 thread. Prints a
# table of runs/hour; never fails on time. Benchmarks are not tests: run it by hand.
#
#   bench/sweep_bench.sh [BUILD_DIR] [DURATION_S]
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-"$root/build"}
duration=${2:-0.5}
netlab="$build/app/netlab"
[ -x "$netlab" ] || { echo "sweep_bench: no $netlab (build the netlab target)" >&2; exit 1; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

study=("$root/scenarios/net_a_0.5.yaml" --vary drag.drag_coefficient=0.8:1.6:3
       --vary nets.0.corner_mass=0.01:0.03:3 --set "duration=$duration" --json --quiet)

# Prints "| how | runs | failed | wall s | runs/hour |" from the JSON summary on stdin.
row() {
  python3 -c '
import json, sys
s = json.loads(sys.stdin.read().strip().splitlines()[-1])
print("| %s | %d | %d | %.1f | %.0f |" % (sys.argv[1], s["runs"], s["failed"], s["wall_s"],
                                           s["runs_per_hour"]))' "$1"
}

echo "netlab sweep: Net A, ${duration} s of flight per run, 3 x 3 grid (drag coefficient x corner mass)"
echo "machine: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
echo
echo "| pool | runs | failed | wall (s) | runs/hour |"
echo "|---|---|---|---|---|"
"$netlab" sweep "${study[@]}" --jobs 1 --out "$out/j1.h5" | row "1 process, 1 thread"
"$netlab" sweep "${study[@]}" --jobs 2 --out "$out/j2.h5" | row "1 process, 2 threads"
if command -v mpirun >/dev/null && "$netlab" sweep --help >/dev/null &&
   python3 -c 'import json,sys; sys.exit(0 if json.loads(sys.stdin.read().splitlines()[-1])["mpi"] else 1)' \
     < <("$netlab" sweep "${study[@]}" --set duration=0.01 --jobs 1 --out "$out/probe.h5"); then
  root_flag=""
  [ "$(id -u)" -eq 0 ] && root_flag="--allow-run-as-root"
  mpirun -np 2 --oversubscribe $root_flag "$netlab" sweep "${study[@]}" --out "$out/mpi.h5" |
    row "2 MPI ranks, 1 thread each"
else
  echo "| 2 MPI ranks | (netlab built without MPI, or no mpirun) | | | |"
fi
