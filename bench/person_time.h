#pragma once
// A person's time for the labeling actions the benchmarks' scripted people perform, from the
// keystroke-level model of human-computer interaction (Card, Moran & Newell 1980; Kieras 2001):
// a key press K = 0.28 s, pointing with the mouse P = 1.1 s, a button press B = 0.2 s (down and
// up), a mental act (deciding what to do next) M = 1.35 s. Two costs the model leaves to the
// task are set from what the workstation shows (docs/gui.md, "A person's time"):
//   * a look at a review item: its reason read and the knot looked at in the four views the
//     window shows side by side, ~1 s a view: 4 s;
//   * a knot searched for: no ring marks it, so the person finds it by its row and column in
//     the net (counting from labeled neighbours) or by its yarns' colours: 5 s.
// Each action of a script is the sum of its parts; the benchmarks print the total in minutes
// and per knot-frame, and extrapolate it to a whole 6 s shot.

namespace netlab::bench {

struct PersonTime {
  static constexpr double kKey = 0.28;        // K
  static constexpr double kPoint = 1.1;       // P
  static constexpr double kButton = 0.2;      // B
  static constexpr double kDecide = 1.35;     // M
  static constexpr double kReviewLook = 4.0;  // a review item looked at in four views
  static constexpr double kSearch = 5.0;      // a knot without a ring found in the image

  // An aimed click (Find Node's brush on a knot, a seed, a knot placed by hand).
  static constexpr double AimedClick() { return kDecide + kPoint + kButton; }
  // Find Node on a knot the engine flagged (its ring shown, with the reason).
  static constexpr double FindNodeOnReview() { return kReviewLook + AimedClick(); }
  // Find Node on a visible knot the engine left without a label.
  static constexpr double FindNodeOnMissing() { return kSearch + AimedClick(); }
  // The knot placed by hand after Find Node gave nothing usable (the knot is already found).
  static constexpr double PlaceByHand() { return AimedClick(); }
  // A review label on a knot that is not visible, deleted or marked hidden (a look, a key).
  static constexpr double DeleteReview() { return kReviewLook + kDecide + kKey; }
  // A seed: a corner found and clicked.
  static constexpr double Seed() { return kSearch + AimedClick(); }
  // A key that only moves to the next item or runs a tool (Space, T, G, Enter).
  static constexpr double Key() { return kKey; }
  // Fill Grid's preview: G, a look at the preview in the current view, Enter.
  static constexpr double FillGrid() { return 2 * kKey + kDecide + 1.0; }
};

// A 6 s shot at 179 frames per second.
constexpr int kShotFrames = 1074;

}  // namespace netlab::bench
