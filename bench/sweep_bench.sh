#!/usr/bin/env bash
# The sweep's throughput: one realistic short study -- Net A's first half
# second of flight (scenarios/net_a_0.5.yaml, 11 x 11 knots, 880 segments), the drag coefficient
# x the corner mass on a 3 x 3 grid -- run by `netlab sweep` with 1 and 2 threads and, when
# netlab is built with MPI and mpirun is there, by 2 MPI ranks of 1 thread. Prints a table of
# runs/hour, with the CPU time the runs took and how many cores that was on average (on a shared
# machine, what the others left); never fails on time. Run it by hand:
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

# Runs "$@" (a netlab sweep printing its JSON), then prints the table's row named $name.
row() {
  local name=$1
  shift
  local TIMEFORMAT='%U %S %R'
  { time "$@" > "$out/json.txt" ; } 2> "$out/time.txt"
  python3 - "$name" "$out/json.txt" "$out/time.txt" <<'PY'
import json, sys
name, json_path, time_path = sys.argv[1:]
s = json.loads(open(json_path).read().strip().splitlines()[-1])
user, system, real = map(float, open(time_path).read().split()[-3:])
print("| %s | %d | %d | %.1f | %.1f | %.2f | %.0f |" % (
    name, s["runs"], s["failed"], s["wall_s"], user + system, (user + system) / real,
    s["runs_per_hour"]))
PY
}

echo "netlab sweep: Net A, ${duration} s of flight per run, 3 x 3 grid (drag coefficient x corner mass)"
echo "machine: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
echo
echo "| pool | runs | failed | wall (s) | CPU (s) | cores used | runs/hour |"
echo "|---|---|---|---|---|---|---|"
row "1 process, 1 thread" "$netlab" sweep "${study[@]}" --jobs 1 --out "$out/j1.h5"
row "1 process, 2 threads" "$netlab" sweep "${study[@]}" --jobs 2 --out "$out/j2.h5"
mpi=$("$netlab" sweep "${study[@]}" --set duration=0.01 --jobs 1 --out "$out/probe.h5" |
      python3 -c 'import json, sys; print(json.loads(sys.stdin.read().splitlines()[-1])["mpi"])')
if [ "$mpi" = True ] && command -v mpirun > /dev/null; then
  root_flag=()
  [ "$(id -u)" -eq 0 ] && root_flag=(--allow-run-as-root)
  row "2 MPI ranks, 1 thread each" mpirun -np 2 --oversubscribe "${root_flag[@]}" \
    "$netlab" sweep "${study[@]}" --out "$out/mpi.h5"
else
  echo "| 2 MPI ranks | netlab built without MPI, or no mpirun | | | | | |"
fi
echo
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
