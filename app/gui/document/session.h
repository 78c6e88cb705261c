#pragma once
// One open project, without a window: the recording (frames through a bounded cache), the rig,
// the net's colouring, the labels document and the engine's tools as undoable steps. The window
// draws what a Session holds and forwards the person's actions to it; tests drive it directly.
//
//   auto session = Session::Open(LoadProject("project.yaml"));   // InputError names the file
//   session->FindNode(camera, t, knot, click_px, 6.0);           // one undo step
//   auto run = session->Track(session->document().labels(), t, t + 30, &cancel);  // any thread
//   session->ApplyTrackRun(run);                                 // GUI thread: one undo step
//   auto preview = session->PreviewFillGrid(session->document().labels(), t);  // any thread
//   session->ApplyFillGridPreview(preview);                      // GUI thread: one undo step
//
// Frame rows t = 0 .. frames() - 1 are the recording's frames first_frame() + t.

#include <Eigen/Core>
#include <array>
#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "app/gui/document/label_document.h"
#include "app/gui/document/missing_knots.h"
#include "app/gui/document/project.h"
#include "calibration/rig.h"
#include "common/progress.h"
#include "libreconstruct/geometry/triangulation.h"
#include "libreconstruct/labeling/label_engine.h"
#include "libreconstruct/recording/frame_cache.h"
#include "libreconstruct/recording/sequence.h"

namespace netlab::gui {

class Session {
 public:
  // Opens the project's files: InputError (or std::runtime_error) naming the file and what is
  // wrong. The labels file is read when it exists (its net and cameras must match), else the
  // labels start empty.
  static std::unique_ptr<Session> Open(const Project& project,
                                       recon::FrameCacheOptions cache_options = {});
  ~Session();

  const Project& project() const { return project_; }
  const recon::SynchronizedSequence& sequence() const { return *sequence_; }
  recon::FrameCache& cache() { return *cache_; }
  const calib::Rig& rig() const { return rig_; }
  LabelDocument& document() { return *document_; }
  const LabelDocument& document() const { return *document_; }
  int cameras() const { return static_cast<int>(camera_names_.size()); }
  const std::vector<std::string>& camera_names() const { return camera_names_; }
  int frames() const { return static_cast<int>(frame_numbers_.size()); }
  int frame_number(int t) const { return frame_numbers_[t]; }
  const std::vector<int>& frame_numbers() const { return frame_numbers_; }
  double fps() const { return sequence_->experiment().fps; }
  // The rig camera of store camera c.
  const calib::Camera& rig_camera(int c) const { return rig_.cameras[rig_index_[c]]; }

  // The full-resolution BGR image of (camera, t) from the cache; empty with the reason when it
  // cannot be read. Thread-safe.
  cv::Mat Image(int camera, int t, std::string* error = nullptr) const;

  // The tools, each one undoable step (GUI thread). Find Node: the person's brush (never a
  // guess: none or several leave the labels as they were). After the person's label (found with
  // the brush, placed or accepted) the knot's other labels of the frame are checked against it
  // (LabelEngine::CheckAgainstPerson): a step of its own where it turns some to review.
  recon::FindNodeResult FindNode(int camera, int t, int knot, const Eigen::Vector2d& centre,
                                 double radius_px);
  // A label exactly where the person put it (source: person, accepted). Also accepts and corrects
  // a derived or doubtful label in one gesture (a drag ends here).
  void PlaceLabel(int camera, int t, int knot, const Eigen::Vector2d& px,
                  const std::string& step = "Place");
  void AcceptLabel(int camera, int t, int knot);
  void DeleteLabel(int camera, int t, int knot);
  // Find Path between two labeled knots of one row or column in (camera, t): the knots between
  // labeled (accepted: the path's junctions are evenly spaced, or it is refused). Returns the
  // refusal's reason, "" on success.
  std::string FindPathBetween(int camera, int t, int knot_a, int knot_b);
  // Find Path from the four seeded corners in every camera that has them, then the epipolar
  // check and Fill Grid (the first frame of netlab label).
  recon::EngineCounts FindPathFromCorners(int t);
  // The epipolar check and Fill Grid in frame t.
  recon::EngineCounts FillGrid(int t);

  // What FillGrid(t) (from_corners: FindPathFromCorners(t)) would change, computed on `snapshot`
  // (document().labels(), copied on the GUI thread) by an engine of its own: any thread, never
  // touches the document. It starts from the link length the GUI thread's engine has (the project's
  // mesh, or its estimate once made), so that applying it (ApplyFillGridPreview) gives exactly the
  // labels FillGrid(t) gives.
  struct FillGridPreview {
    int t = 0;
    // Find Path from the corners first (Ctrl+P): applied as two steps, "Find Path from the
    // corners" (path_edits) and "Fill Grid" (check_edits), as FindPathFromCorners makes them.
    bool from_corners = false;
    std::vector<recon::LabelEdit> path_edits, check_edits;
    // The labels that differ from the snapshot's, as the check and Fill Grid leave them.
    std::vector<recon::LabelEdit> edits;
    recon::ReviewReasons reasons;  // why labels are kept for review (the engine's, this run)
    double link_length_m = 0.0;    // the link length the run used or estimated (m; 0: none)
    recon::LabelEngine::KnotsInFrames one_path;  // its labels found along one path alone
    int added = 0;                               // labels where there was none
    int added_review = 0;                        // ... of them kept for review
    int to_review = 0;                           // accepted labels the checks turn to review
    int confirmed = 0;  // labels under review accepted (at the junction the check found)
    int moved = 0;      // accepted labels moved (flagged, then found again elsewhere)
    int changed = 0;    // any other change (a label removed, say)
    bool empty() const { return edits.empty(); }
  };
  FillGridPreview PreviewFillGrid(recon::LabelSet snapshot, int t, bool from_corners = false) const;
  // Applies a preview as one undo step "Fill Grid", its reasons merged into the document (GUI
  // thread). The caller makes sure the labels have not changed since its snapshot. Returns the
  // labels changed.
  int ApplyFillGridPreview(const FillGridPreview& preview);
  // The net's link length the GUI thread's engine judges with (m): the project's mesh, else its
  // estimate from the first cross-checked frame (or an applied preview's); 0 until then.
  double link_length_m() const { return link_length_m_; }

  // A tracking run from labeled row `from` towards `to` on `snapshot` (document().labels(),
  // copied on the GUI thread); runs on any thread and never touches the document. Stops when
  // the reporter's token is cancelled (the run says cancelled and keeps the frames it went
  // through), or after a frame with more than max_review labels kept for review (0: the first
  // frame with one; negative: no limit). Progress: stage "frames tracked", from the running
  // thread.
  struct TrackRun {
    int from = 0, to = 0, last_done = 0;
    bool cancelled = false, stopped_for_review = false;
    std::vector<recon::LabelEdit> edits;  // the rows it went through, as it left them
    recon::ReviewReasons reasons;
  };
  TrackRun Track(recon::LabelSet snapshot, int from, int to, const ProgressReporter& progress = {},
                 int max_review = -1) const;
  // Applies a run as one undo step (GUI thread). Returns the labels changed.
  int ApplyTrackRun(const TrackRun& run);

  // The colour check of a label of `knot` at `px` in (camera, t) (netlab label's,
  // label_identity.h): the link colours its code expects and what the yarns there say. `yarns`:
  // recon::AcceptedNeighbourYarns of the labels (which yarn is which link, as the engine reads
  // them). Any thread (the frame comes from the cache, decoded there if need be): call it off the
  // GUI thread. nullopt without a colouring or a readable frame.
  struct KnotColours {
    struct Link {
      std::string side;  // "right", "down", "left", "up": towards which grid neighbour
      std::string dye;   // the palette colour's name
      std::array<double, 3> srgb{0, 0, 0};  // as the camera sees it, for a swatch (R, G, B)
    };
    std::vector<Link> expected;
    recon::IdentityVerdict verdict = recon::IdentityVerdict::kUnreadable;
    std::string why;              // the check's line for the reviewer
    std::vector<int> knots_read;  // the knots the colours fit (one: identified)
    bool read = true;             // false: the expected colours alone (no label to read at)
  };
  std::optional<KnotColours> CheckKnotColours(int camera, int t, int knot,
                                              const Eigen::Vector2d& px,
                                              const recon::YarnDirections& yarns) const;
  // The link colours `knot`'s code expects, without reading the image (`read` false): what the
  // person looks for at a knot that has no label yet. nullopt without a colouring.
  std::optional<KnotColours> ExpectedColours(int knot) const;

  // The knot picker's hint: which knot the junction inside the brush (centre, radius in px) of
  // (camera, t) is, from its yarn colours (recon::ReadJunctionIdentity). Knots with an accepted
  // label elsewhere in this view (farther than the brush) are not offered; a corner mass offers
  // the net's corners that fit. Nothing is labeled: the person picks. GUI thread (a few ms once
  // the frame is cached).
  struct JunctionHint {
    bool found = false;  // Find Node found one junction (or corner mass) in the brush
    Eigen::Vector2d px = Eigen::Vector2d::Zero();  // where
    bool corner_mass = false;
    double link_px = 0.0;            // the link length the yarns were read against (0: unknown)
    recon::JunctionReading reading;  // reading.why also says why nothing was found
  };
  // `link_px` < 0: the link length from the labels (LinkLengthPx); else the one given (0: unknown).
  JunctionHint IdentifyJunction(int camera, int t, const Eigen::Vector2d& centre, double radius_px,
                                double link_px = -1) const;
  // The median image length (px) of the net's links whose both ends have accepted labels in
  // (camera, t), else in the nearest frame row of that camera that has some; 0 when none.
  double LinkLengthPx(int camera, int t) const;

  // The knot's point from the accepted labels of frame t (two views or more), with the
  // reprojection residual per view.
  recon::PointEstimate Triangulate(int t, int knot) const;
  // Where a label (camera `from`, pixel px) can be in camera `to`: its viewing ray, projected
  // through `to`'s lens distortion, as a polyline (depths 0.2 .. 20 m; points behind `to` or
  // outside its image are left out, splitting the curve).
  std::vector<std::vector<Eigen::Vector2d>> EpipolarCurve(int from, const Eigen::Vector2d& px,
                                                          int to) const;

  // Missing knots (missing_knots.h): visible knots with no label in a camera where two or more
  // others have accepted labels; kept up to date with the document.
  const MissingKnots& missing() const { return *missing_; }
  // The person's word that `knot` is not visible in (camera, t): a hidden mark in place of
  // whatever is there, one undo step; the tools never label over it. Returns the labels changed.
  int MarkHidden(int camera, int t, int knot);
  // The same in t and every following frame row in which (camera, knot) is missing without a
  // break (MissingKnots::RunFrom), as one undo step. Returns the last frame row marked (-1:
  // none, the knot is not missing in t).
  int MarkHiddenRun(int camera, int t, int knot);

 private:
  // LabelEngine::CheckAgainstPerson for the person's label in (camera, t) of `knot`, its reasons
  // merged into the document.
  void CheckAgainstPerson(int camera, int t, int knot);
  Session() = default;
  std::unique_ptr<recon::LabelEngine> MakeEngine(recon::LabelStore* store) const;
  recon::LabelEngine& engine();

  Project project_;
  std::unique_ptr<recon::SynchronizedSequence> sequence_;
  std::unique_ptr<recon::FrameCache> cache_;
  calib::Rig rig_;
  std::vector<int> rig_index_;
  std::vector<std::string> camera_names_;
  std::vector<int> frame_numbers_;
  std::optional<recon::KnotCodebook> codebook_;
  recon::IdentityCheckOptions identity_;
  recon::LabelEngineOptions engine_options_;
  recon::Target target_;  // project.yaml's target: its engines doubt labels of knots it hides
  std::unique_ptr<LabelDocument> document_;
  std::unique_ptr<recon::LabelEngine> engine_;  // over the document's store (GUI thread)
  std::unique_ptr<MissingKnots> missing_;       // over the document (destroyed before it)
  // engine_'s link length (m; 0: not known yet), for the previews on other threads: set on the
  // GUI thread after each of its cross-checks (the only step that estimates it).
  std::atomic<double> link_length_m_{0.0};
  void NoteLinkLength() { link_length_m_ = engine().link_length_m(); }
  // engine_'s labels found along one path alone (LabelEngine::one_path), for the engines of the
  // other threads, which adopt them: set on the GUI thread after each step that finds some.
  mutable std::mutex one_path_mutex_;
  recon::LabelEngine::KnotsInFrames one_path_;
  void NoteOnePath() {
    const std::lock_guard<std::mutex> lock(one_path_mutex_);
    one_path_ = engine().one_path();
  }
};

}  // namespace netlab::gui
