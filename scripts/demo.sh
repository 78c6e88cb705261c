#!/usr/bin/env bash
# Sets up a fresh Debian machine (missing packages, build), then runs netlab's whole loop on the
# synthetic experiment, the digital twin of a parabolic-flight shot:
#   1. simulate the first second of Net A shot at 0.5 m/s (scenarios/net_a_0.5.yaml), and the same
#      shot with a wrong model (no air drag: what the scoring must reject);
#   2. colour the net's yarns and film the first 40 frames of the shot with the paper's four-camera
#      rig (raw 2048x2048 Bayer frames, truth, and calibration images of the double-sided foil);
#   3. calibrate the rig from the rendered foil images and print its errors against the true rig;
#   4. label the knots with `netlab label` from the corners of the first frame in each camera that
#      it sees (taken from the truth: they stand for a person's clicks);
#   5. triangulate the labels with the calibrated rig into 3D tracks with covariances;
#   6. score the tracks against the simulation that made the shot (consistent) and against the
#      wrong one (rejected), each with an HTML report.
# Everything lands in out/demo/. NETLAB_DEMO_SCALE and NETLAB_DEMO_FRAMES change the size.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
netlab_build

netlab="$NETLAB_BUILD_DIR/app/netlab"
out="$NETLAB_ROOT/out/demo"
scale=${NETLAB_DEMO_SCALE:-1}
frames=${NETLAB_DEMO_FRAMES:-0:39}
rm -rf "$out"
mkdir -p "$out"
SECONDS=0

echo "== 1/6 simulate: Net A at 0.5 m/s, first second of flight; and without air drag" >&2
"$netlab" simulate "$NETLAB_ROOT/scenarios/net_a_0.5.yaml" --duration 1.0 --out "$out/sim.h5" \
  --quiet
# The wrong model: the same scenario without its drag line (data files from the scenario folder).
sed -e '/^drag:/d' -e "s|file: data/|file: $NETLAB_ROOT/scenarios/data/|" \
  "$NETLAB_ROOT/scenarios/net_a_0.5.yaml" > "$out/net_a_0.5_no_drag.yaml"
"$netlab" simulate "$out/net_a_0.5_no_drag.yaml" --duration 1.0 --out "$out/sim_no_drag.h5" \
  --quiet

echo "== 2/6 colour the yarns; render frames $frames through the paper's rig at scale $scale" >&2
"$netlab" color-net --knots 11x11 --out "$out/coloring.yaml" --quiet
"$netlab" render --sim "$out/sim.h5" --out "$out/shot" --frames "$frames" --scale "$scale" \
  --coloring "$out/coloring.yaml"

echo "== 3/6 calibrate from the rendered foil images, compare with the true rig" >&2
images=()
for camera in cam0 cam1 cam2 cam3; do
  images+=(--images "$camera=$out/shot/calibration/$camera/*.png")
done
"$netlab" calibrate --board "$out/shot/calibration/foil.yaml" "${images[@]}" \
  --out "$out/rig_calibrated.yaml" --truth "$out/shot/rig_true.yaml"

echo "== 4/6 label: Find Path and tracking from the corners of frame 0 in each camera" >&2
# The corners each camera sees in the first frame: 3 in each rear camera (the target hides one),
# 1 in each front one (which gets its labels where the rear pair's knots project).
python3 "$NETLAB_ROOT/scripts/seed_corners.py" "$out/shot/truth.h5" 11x11 "$out/seeds.csv" \
  cam0 cam1 cam2 cam3
"$netlab" label "$out/shot/experiment.yaml" --rig "$out/rig_calibrated.yaml" \
  --coloring "$out/coloring.yaml" --seed "$out/seeds.csv" --out "$out/labels.h5"

echo "== 5/6 triangulate the labels with the calibrated rig" >&2
# --sigma-px 0.09: the labels' accuracy on the twin (RMS 0.074 px per coordinate against the
# truth, with a tail to 0.33 px at the 99th percentile: docs/labeling.md); the reprojection
# residuals alone (0.068 px) miss the error the cameras of a pair share. --experiment: the frames'
# times from the cameras' timestamps; --estimate-offsets: each camera's sub-frame clock offset
# from the knots' motion, reported (the twin's cameras are synchronised: all within 0.02 frames).
"$netlab" triangulate --rig "$out/rig_calibrated.yaml" --labels "$out/labels.h5" \
  --knots 11x11 --fps 179 --sigma-px 0.09 --out "$out/tracks.h5" --csv "$out/" \
  --truth "$out/sim.h5" --experiment "$out/shot/experiment.yaml" --estimate-offsets

echo "== 6/6 score the tracks against the true simulation and against the one without drag" >&2
# The calibrated rig has the foil's world frame, not the scenario's: fit one rigid motion (and the
# launch-time offset) per score.
score() {  # measured sim name
  "$netlab" score --measured "$1" --sim "$2" --out "$out/$3.h5" --report "$out/$3.html" \
    --align time+rigid --json > "$out/$3.json"
}
score "$out/tracks.h5" "$out/sim.h5" score
score "$out/tracks.h5" "$out/sim_no_drag.h5" score_no_drag

verdict() { sed -e 's/.*"verdict":"\([a-z]*\)".*/\1/' "$1"; }
echo "demo: done in ${SECONDS} s." >&2
echo "  true simulation:    $(verdict "$out/score.json")   (report: $out/score.html)" >&2
echo "  no-drag simulation: $(verdict "$out/score_no_drag.json")" \
  "  (report: $out/score_no_drag.html)" >&2
echo "  frames, truth and calibration images in $out/shot; rig in $out/rig_calibrated.yaml;" \
  "labels in $out/labels.h5; 3D tracks in $out/tracks.h5" >&2
# The finished project: the shot, the rig, the labels, their tracks, both simulations and
# their scores (the labeling room's Net grid colours each knot by its saved error at once; the
# simulation room scores them again as step 6 did, time+rigid, and shows the verdicts).
cat > "$out/project.yaml" <<EOF
netlab_project: 1
experiment: shot/experiment.yaml
rig: rig_calibrated.yaml
coloring: coloring.yaml
labels: labels.h5
tracks: tracks.h5
simulations: [sim.h5, sim_no_drag.h5]
scores:
  - {simulation: sim.h5, score: score.h5, report: score.html}
  - {simulation: sim_no_drag.h5, score: score_no_drag.h5, report: score_no_drag.html}
EOF
echo "  the project in $out/project.yaml; open it in the workstation on the verdicts" \
  "(docs/gui.md):" >&2
echo "    $netlab gui $out/project.yaml --room simulation" >&2
