#pragma once
// What a camera view draws over its frame: the labels, the links, the selected knot's epipolar
// curves and reprojection, the expected place of a missing knot, Find Node's candidates, a
// pending preview's ghosts, a simulated net and the caption. Made without a window by the
// labeling presenter (labeling_presenter.h) and the simulation room; CameraView paints it.

#include <Eigen/Core>
#include <QColor>
#include <QString>
#include <cmath>
#include <optional>
#include <utility>
#include <vector>

namespace netlab::gui {

// What a view draws over its frame, for the current frame and camera.
struct ViewOverlay {
  struct Mark {
    int knot = -1;
    Eigen::Vector2d px;
    QColor colour;
    bool review = false;
  };
  std::vector<Mark> labels;
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> links;  // between labeled neighbours
  int selected_knot = -1;
  std::vector<std::vector<Eigen::Vector2d>> epipolar;  // curves from the other cameras' labels
  std::optional<Eigen::Vector2d> reprojected;          // the selected knot's triangulated point
  // The selected knot missing in this view (no label, two other cameras see it): where they put
  // it, drawn as a ring so it is found when zoomed out.
  std::optional<Eigen::Vector2d> expected;
  std::vector<Eigen::Vector2d> candidates;  // Find Node's when it found several
  // A pending Fill Grid preview: what accepting it would do here, drawn dashed (not labels yet).
  struct Ghost {
    enum Kind {
      kNew,       // a label where there is none: a dashed circle (accepted) or diamond (review)
      kToReview,  // an accepted label the check would turn to review: a dashed diamond round it
      kChanged,   // a label that would move or change state (one under review accepted, say):
                  // dashed at its new place, with a line from where it is
      kRemoved,   // a label that would be removed: a dashed cross
    } kind = kNew;
    int knot = -1;
    Eigen::Vector2d px;  // where the label would be (the label's own place for kToReview)
    Eigen::Vector2d from = Eigen::Vector2d::Constant(NAN);  // kChanged: where it is now
    bool review = false;                                    // the label would be kept for review
  };
  std::vector<Ghost> ghosts;
  // A simulated net over the frame (the simulation room): its knots as squares and its links as
  // lines, in their mark's colour, drawn under the labels.
  std::vector<Mark> simulated;
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> simulated_links;
  QColor simulated_colour = QColor(0, 230, 255);
  QString caption;  // camera, frame, residual
};

}  // namespace netlab::gui
