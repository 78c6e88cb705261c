#!/usr/bin/env bash
# Sets up a fresh Debian machine (missing packages, build), then runs the whole test suite.
# Extra arguments go to ctest (e.g. scripts/test.sh -R Statics).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
netlab_build
cd "$NETLAB_BUILD_DIR"
ctest --output-on-failure -j2 "$@"
