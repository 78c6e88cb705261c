#pragma once
// Where the person is in the open project, shared by every room: the frame row, the camera they
// work in and the knot the tools label (the knot picker). It keeps each inside the project's
// limits and remembers the knot picked before the current one (Find Path to the previous knot).
//
//   Cursor cursor;
//   cursor.Reset(frames, cameras, rows, cols);   // frame -1 (none shown yet), camera 0, knot 0
//   cursor.SetFrame(40);                          // clamped to 0 .. frames - 1; false: unchanged
//   cursor.KnotName(cursor.knot());               // "(0, 0)"

#include <QString>

namespace netlab::gui {

class Cursor {
 public:
  // A project of `frames` frame rows, `cameras` cameras and a rows x cols net: no frame shown
  // yet (frame() is -1), camera 0, knot 0, no previous knot.
  void Reset(int frames, int cameras, int rows, int cols);

  int frame() const { return frame_; }
  int camera() const { return camera_; }
  int knot() const { return knot_; }
  int previous_knot() const { return previous_knot_; }  // -1: none
  int frames() const { return frames_; }
  int cameras() const { return cameras_; }
  int rows() const { return rows_; }
  int cols() const { return cols_; }
  int knots() const { return rows_ * cols_; }

  // Moves to frame row t clamped to the recording; false when that is where it is (or no
  // project). `direction` (when given): +1 forwards, -1 backwards, 0 from no frame.
  bool SetFrame(int t, int* direction = nullptr);
  // Makes camera c current; false (unchanged) when there is no such camera.
  bool SetCamera(int c);
  // Picks knot k clamped to the net; the knot before becomes previous_knot() when it changes.
  void SetKnot(int k);

  // "(row, col)" of knot k.
  QString KnotName(int k) const;

 private:
  int frames_ = 0, cameras_ = 0, rows_ = 0, cols_ = 1;
  int frame_ = -1, camera_ = 0, knot_ = 0, previous_knot_ = -1;
};

}  // namespace netlab::gui
