#!/usr/bin/env bash
# Sets up a fresh Debian machine (missing packages, build), then runs netlab's main job on the
# synthetic experiment, the digital twin of a parabolic-flight shot:
#   1. simulate the first second of Net A shot at 0.5 m/s (scenarios/net_a_0.5.yaml);
#   2. film it with the paper's four-camera rig at half resolution (raw Bayer frames, truth, and
#      calibration images of the double-sided checker foil);
#   3. check the recording as netlab reads any recording (netlab ingest);
#   4. calibrate the rig from the rendered foil images and print its errors against the true rig;
#   5. triangulate the knots from their true pixels (labels_true.h5, a perfect labeling) with the
#      calibrated rig and compare the 3D tracks with the simulation.
# Everything lands in out/demo/. NETLAB_DEMO_SCALE and NETLAB_DEMO_FRAMES change the size.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
netlab_build

netlab="$NETLAB_BUILD_DIR/app/netlab"
out="$NETLAB_ROOT/out/demo"
scale=${NETLAB_DEMO_SCALE:-0.5}
frames=${NETLAB_DEMO_FRAMES:-0:59}
rm -rf "$out"
mkdir -p "$out"
SECONDS=0

echo "== 1/5 simulate: Net A at 0.5 m/s, first second of flight" >&2
"$netlab" simulate "$NETLAB_ROOT/scenarios/net_a_0.5.yaml" --duration 1.0 --out "$out/sim.h5"

echo "== 2/5 render: frames $frames through the paper's rig at scale $scale" >&2
"$netlab" render --sim "$out/sim.h5" --out "$out/shot" --frames "$frames" --scale "$scale"

echo "== 3/5 ingest: check the rendered recording" >&2
"$netlab" ingest "$out/shot/experiment.yaml" --check --decode

echo "== 4/5 calibrate from the rendered foil images, compare with the true rig" >&2
images=()
for camera in cam0 cam1 cam2 cam3; do
  images+=(--images "$camera=$out/shot/calibration/$camera/*.png")
done
"$netlab" calibrate --board "$out/shot/calibration/foil.yaml" "${images[@]}" \
  --out "$out/rig_calibrated.yaml" --truth "$out/shot/rig_true.yaml"

echo "== 5/5 triangulate the labeled knots with the calibrated rig, compare with the simulation" >&2
"$netlab" triangulate --rig "$out/rig_calibrated.yaml" --labels "$out/shot/labels_true.h5" \
  --knots 11x11 --fps 179 --out "$out/tracks.h5" --csv "$out/" --truth "$out/sim.h5"

echo "demo: done in ${SECONDS} s. Frames, truth and calibration images in $out/shot;" \
  "calibrated rig in $out/rig_calibrated.yaml; 3D tracks in $out/tracks.h5 and" \
  "$out/xyzpts.csv" >&2
