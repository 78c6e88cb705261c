#!/usr/bin/env bash
# Sets up a fresh Debian machine (missing packages, build), then runs the whole test suite,
# the check of the code's format (scripts/check_format.sh) among it.
# Extra arguments go to ctest (e.g. scripts/test.sh -R Statics).
set -euo pipefail
netlab_extra_packages=(clang-format)  # the test format_check (scripts/check_format.sh)
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
netlab_build
cd "$NETLAB_BUILD_DIR"
ctest --output-on-failure -j2 "$@"
