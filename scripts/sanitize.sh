#!/usr/bin/env bash
# The sanitizer run: netlab and its tests built with AddressSanitizer (leaks included) and
# UndefinedBehaviorSanitizer (-DNETLAB_SANITIZE=ON, RelWithDebInfo), then the whole ctest suite.
# Every report of any process the suite starts (the test binaries and each `netlab` they run) is
# written to a log file, not to the process's stderr, so a bad-input row cannot mistake a report
# for netlab's own message; the run fails when a test fails or any report was written, and prints
# the reports. Too slow for CI (scripts/test.sh): on 2 cores the build alone takes hours.
#
#   scripts/sanitize.sh                  # everything
#   scripts/sanitize.sh -R BadInput      # extra arguments go to ctest
#
# Environment: NETLAB_SANITIZE_BUILD_DIR (default build-sanitize/), NETLAB_JOBS (default: the
# cores; the build and ctest alike). docs/bad_input.md says what a run found.
set -euo pipefail
NETLAB_BUILD_DIR=${NETLAB_SANITIZE_BUILD_DIR:-"$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/build-sanitize"}
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
jobs=${NETLAB_JOBS:-$(nproc)}

cmake -S "$NETLAB_ROOT" -B "$NETLAB_BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DNETLAB_SANITIZE=ON -DNETLAB_BUILD_BENCH=OFF >/dev/null
cmake --build "$NETLAB_BUILD_DIR" -j"$jobs"

logs="$NETLAB_BUILD_DIR/sanitizer-logs"
rm -rf "$logs"
mkdir -p "$logs"
# halt_on_error: the first error ends the process (exit 86 or 87, which no test expects).
# detect_leaks: LeakSanitizer at exit, with tests/lsan.supp (third-party libraries' own
# allocations only). check_initialization_order: static initialisers reading other files'
# globals. UBSan is built with -fno-sanitize-recover, so its first report ends the process too.
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:check_initialization_order=1:strict_init_order=1:exitcode=86:log_path=$logs/asan"
export LSAN_OPTIONS="suppressions=$NETLAB_ROOT/tests/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:exitcode=87:log_path=$logs/ubsan"
export QT_QPA_PLATFORM=${QT_QPA_PLATFORM:-offscreen}

cd "$NETLAB_BUILD_DIR"
status=0
ctest --output-on-failure -j"$jobs" "$@" || status=$?
reports=$(find "$logs" -type f | sort)
if [ -n "$reports" ]; then
  echo "sanitize.sh: $(echo "$reports" | wc -l) sanitizer report(s) in $logs:" >&2
  for f in $reports; do
    echo "---- $f" >&2
    head -60 "$f" >&2
  done
  exit 1
fi
[ "$status" -eq 0 ] && echo "sanitize.sh: the suite passed with no sanitizer report" >&2
exit "$status"
