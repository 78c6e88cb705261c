#!/usr/bin/env bash
# Sets up a fresh Debian machine (missing packages, build), then runs netlab's main job.
# Until the reconstruction lands, that is the paper's net-capture case (section 3): a 1 x 1 m
# polypropylene net with four 0.5 kg corner masses falling onto a rigid sphere.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
netlab_build

out="$NETLAB_ROOT/out"
mkdir -p "$out"
"$NETLAB_BUILD_DIR/app/netlab" simulate "$NETLAB_ROOT/scenarios/net_capture.yaml" \
  --out "$out/net_capture.h5"
echo "demo: knot tracks written to $out/net_capture.h5"
