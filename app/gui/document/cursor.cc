#include "app/gui/document/cursor.h"

#include <algorithm>

namespace netlab::gui {

void Cursor::Reset(int frames, int cameras, int rows, int cols) {
  frames_ = frames;
  cameras_ = cameras;
  rows_ = rows;
  cols_ = std::max(cols, 1);
  frame_ = -1;
  camera_ = 0;
  knot_ = 0;
  previous_knot_ = -1;
}

bool Cursor::SetFrame(int t, int* direction) {
  if (frames_ <= 0) return false;
  t = std::clamp(t, 0, frames_ - 1);
  if (t == frame_) return false;
  if (direction != nullptr) *direction = frame_ < 0 ? 0 : (t > frame_ ? 1 : -1);
  frame_ = t;
  return true;
}

bool Cursor::SetCamera(int c) {
  if (c < 0 || c >= cameras_) return false;
  camera_ = c;
  return true;
}

void Cursor::SetKnot(int k) {
  if (knots() <= 0) return;
  k = std::clamp(k, 0, knots() - 1);
  if (k != knot_) previous_knot_ = knot_;
  knot_ = k;
}

QString Cursor::KnotName(int k) const { return QString("(%1, %2)").arg(k / cols_).arg(k % cols_); }

}  // namespace netlab::gui
