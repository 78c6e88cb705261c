#pragma once
// The labeling workstation's window: four camera views sharing one frame index, the timeline,
// the review queue, the tools and their shortcuts. It lays out and paints what the labeling
// presenter (document/labeling_presenter.h) makes of the Session's state, and forwards the
// person's actions to the Session; everything it changes goes through the document's undo stack.
//
// Frames are decoded off the GUI thread (the frame cache's prefetch, and a worker for a frame
// not yet cached); a tracking run runs on a worker with progress and Cancel. Each kind of
// background work goes through one LatestRequest (document/latest_request.h).

#include <QMainWindow>
#include <QPointer>
#include <array>
#include <atomic>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "app/gui/camera_view.h"
#include "app/gui/document/calibration_presenter.h"
#include "app/gui/document/cursor.h"
#include "app/gui/document/labeling_presenter.h"
#include "app/gui/document/latest_request.h"
#include "app/gui/document/reconstruction_presenter.h"
#include "app/gui/document/recording_presenter.h"
#include "app/gui/document/review_model.h"
#include "app/gui/document/session.h"
#include "app/gui/document/simulation_presenter.h"

class QLabel;
class QProgressDialog;
class QSortFilterProxyModel;
class QSpinBox;
class QStackedWidget;
class QTabBar;
class QTableView;
class QTimer;
class QGridLayout;

namespace netlab::gui {

class CalibrationRoom;
class CameraView;
class KnotGrid;
class RecordingRoom;
class ReconstructionRoom;
class SimulationRoom;
class Timeline;
struct ViewOverlay;

class MainWindow : public QMainWindow {
  Q_OBJECT

 public:
  MainWindow();
  ~MainWindow() override;

  // T's tracking run stops after a frame with more labels than this kept for review: at the
  // first frame that needs the person, whose first review item it then shows (a run that went on
  // would carry every doubtful label into the frames after it, each needing a look or a re-run).
  static constexpr int kMaxReviewPerFrame = 0;

  // Opens a project (asks about a journal left by a crash unless `ask` is false, then recovers
  // nothing). False when it cannot be opened: the reason, naming the file, goes to `error` when
  // given (no dialog: the command line prints it), else into a dialog. A path that fails to open
  // leaves the recent projects.
  bool OpenProject(const QString& path, bool ask = true, QString* error = nullptr);
  Session* session() { return session_.get(); }

  // The rooms of an open project, in the order of the work: the recording (ingest check), the
  // calibration (the rig), the labeling, the reconstruction (3D tracks), the simulation (the
  // simulated net over the footage and the score's verdict). The tab bar above them and the Room
  // menu switch them; the labeling room's docks, tool bar and keys belong to it alone.
  enum class Room { kRecording, kCalibration, kLabeling, kReconstruction, kSimulation };
  // Shows a room; without a project only the recording room of an opened recording.
  void ShowRoom(Room room);
  // Opens a recording alone (experiment.yaml, no rig or labels yet) in the recording room; the
  // other rooms wait for a project. False with the reason (naming the file) in `error` when
  // given, else in a dialog.
  bool OpenRecording(const QString& experiment, QString* error = nullptr);
  Room room() const { return room_; }
  RecordingRoom* recording_room() const { return recording_room_; }
  CalibrationRoom* calibration_room() const { return calibration_room_; }
  ReconstructionRoom* reconstruction_room() const { return reconstruction_room_; }
  SimulationRoom* simulation_room() const { return simulation_room_; }
  const RecordingPresenter* recording() const { return recording_.get(); }
  const CalibrationPresenter* calibration() const { return calibration_.get(); }
  SimulationPresenter* simulation() const { return simulation_.get(); }
  ReconstructionPresenter* reconstruction() const { return reconstruction_.get(); }

  // The current frame row, camera (the one the person works in) and knot (the knot picker).
  int frame() const { return cursor_.frame(); }
  int camera() const { return cursor_.camera(); }
  int knot() const { return cursor_.knot(); }
  const Cursor& cursor() const { return cursor_; }
  void SetFrame(int t);
  void SetCamera(int c);
  void SetKnot(int knot);
  CameraView* view(int c) const { return views_[c]; }
  QTableView* review_table() const { return review_table_; }
  KnotGrid* knot_grid() const { return knot_grid_; }
  // Half-resolution display (faster decode and paint at 2048^2).
  void SetHalfResolution(bool half);
  // Shows one camera alone (-1: all four). While one camera is shown alone, a change of the
  // current camera shows that camera alone instead: the view always shows the camera acted on.
  void Maximise(int c);
  int maximised() const { return maximised_; }

  // Waits (processing events) until the current frame is drawn in every view; false after
  // `timeout_ms`.
  bool WaitForFrame(int timeout_ms = 20000);
  // Tracks from the current frame to `to` (worker thread, progress dialog); waits when `wait`.
  // Stops after a frame with more than `max_review` labels for review (negative: no limit).
  void TrackTo(int to, bool wait = false, int max_review = kMaxReviewPerFrame);
  // Whether a tracking run is under way, until its result is applied (the views take no edits
  // meanwhile).
  bool busy() const { return tracking_; }
  // The review queue: the next / previous item (frame, camera maximised, knot selected, zoomed).
  void NextReview(bool backwards = false);
  // The queue's first item: the earliest frame with a label for review.
  void FirstReviewItem();

  // The Fill Grid preview (G): computed on a worker from a snapshot of the labels, drawn as ghost
  // marks with a banner, applied by Enter as one undo step "Fill Grid" or discarded by Esc. Any
  // change of the labels, of the frame, or a tracking run discards it: a preview of other labels
  // is never applied. The pending one (null: none), and whether one is being computed.
  const Session::FillGridPreview* fill_grid_preview() const {
    return preview_ ? &*preview_ : nullptr;
  }
  bool previewing() const { return preview_frame_ >= 0 && !preview_; }
  // Waits (processing events) until the frame is drawn and no preview or tracking run is under
  // way; false after `timeout_ms`.
  bool WaitForIdle(int timeout_ms = 60000);

 protected:
  void closeEvent(QCloseEvent* event) override;
  // The spin boxes of the frame and the knot: they take the keys of a number (digits, editing,
  // steps) only, and only after a click into them; every other key is the window's (A, D, T,
  // ...), and Enter or Esc hands the keys back to the current view.
  bool eventFilter(QObject* watched, QEvent* event) override;

 private:
  void BuildWelcome();
  void BuildRooms();
  // The recording room's check on a worker (once per project), and its answer.
  void StartCheck();
  void OnChecked(recon::CheckReport report);
  void RecordingRoomAction() { ShowRoom(Room::kRecording); }
  void CalibrationRoomAction() { ShowRoom(Room::kCalibration); }
  void LabelingRoomAction() { ShowRoom(Room::kLabeling); }
  void ReconstructionRoomAction() { ShowRoom(Room::kReconstruction); }
  void SimulationRoomAction() { ShowRoom(Room::kSimulation); }
  // The labeling room at a label another room points to (camera -1: the first that has it).
  void ShowLabel(int camera, int t, int knot);
  void BuildWorkspace();
  void BuildActions();
  QAction* AddAction(QMenu* menu, const QString& name, const QString& keys,
                     void (MainWindow::*slot)());
  // The frame being loaded: decoded, reduced to each view's size and toned on a worker.
  struct Loaded {
    int t = 0;
    std::array<ViewFrame, 4> frames;
    std::array<QString, 4> problems;
  };
  void RequestFrame();
  void OnFrameLoaded(Loaded loaded);
  // Gives the keyboard focus to the current camera's view (after a change of camera or frame),
  // unless the person is typing into a spin box they clicked: the labeling keys reach the view.
  void FocusView();
  void RefreshOverlays();
  void RefreshStatus();
  // Goes to row `row` of the review model: its frame, its camera maximised, the knot selected.
  void ShowReviewRow(int row);
  // After the person fixed the queue's item `key` (accepted, deleted, hidden, placed or found
  // again and no longer in doubt): the same frame's next label for review, when "Advance after a
  // fix" is on; its next missing knot only after a missing knot.
  void AdvanceAfterFix(const LabelKey& key, bool was_queued);
  // In the review queue: a label for review or a missing knot.
  bool InQueue(int camera, int t, int knot) const;
  // The Knot colours panel: the selected knot's expected colours at once, then RequestColours
  // reads its yarns (after a short pause, off the GUI thread) when it has a label.
  void ShowColours();
  // The selected knot's colour check in the current camera, on a worker; OnColoursRead shows it.
  void RequestColours();
  void OnColoursRead(std::optional<Session::KnotColours> colours);
  // The tracking run's result applied (GUI thread).
  void OnTracked(Session::TrackRun run);
  void OnLabelsChanged(const QList<int>& frames);
  // The person's actions.
  void OnClick(int camera, const Eigen::Vector2d& px, Qt::KeyboardModifiers modifiers);
  void OnDrag(int camera, int knot, const Eigen::Vector2d& px);
  void OnSelect(int camera, int knot);
  void OnCursor(int camera, const Eigen::Vector2d& px, const QString& value);
  bool MaybeSave();  // asks about unsaved edits: false when the person cancels
  QString KnotName(int knot) const;

  // Actions (slots without arguments, for QAction).
  void NewProject();
  void OpenDialog();
  void OpenRecordingDialog();
  void Save();
  void Undo();
  void Redo();
  void Quit() { close(); }
  void NextFrame() { SetFrame(frame() + 1); }
  void PreviousFrame() { SetFrame(frame() - 1); }
  void Forward10() { SetFrame(frame() + 10); }
  void Back10() { SetFrame(frame() - 10); }
  void FirstFrame() { SetFrame(0); }
  void LastFrame();
  void GoToFrame();
  void TogglePlay();
  void PickCamera1() { SetCamera(0); }  // keys 1-4: the current camera, nothing labeled
  void PickCamera2() { SetCamera(1); }
  void PickCamera3() { SetCamera(2); }
  void PickCamera4() { SetCamera(3); }
  void NextKnot() { SetKnot(knot() + 1); }
  void PreviousKnot() { SetKnot(knot() - 1); }
  void NextReviewItem() { NextReview(false); }
  void PreviousReviewItem() { NextReview(true); }
  void AcceptSelected();
  void DeleteSelected();
  void NudgeLeft() { Nudge(-0.5, 0); }
  void NudgeRight() { Nudge(0.5, 0); }
  void NudgeUp() { Nudge(0, -0.5); }
  void NudgeDown() { Nudge(0, 0.5); }
  void Nudge(double dx, double dy);
  void FindPathCorners();
  void FindPathToPrevious();
  void FillGridHere();
  void TrackForward();
  void TrackBackward();
  void TrackToFrame();
  void ZoomOnKnot();
  void FitAll();
  void ToggleHalf() { SetHalfResolution(!half_); }
  void ToggleMaximise();
  void Brighter() { Tone(1.25, 0, 1); }
  void Darker() { Tone(0.8, 0, 1); }
  void GammaUp() { Tone(1, 0, 0.85); }
  void GammaDown() { Tone(1, 0, 1.0 / 0.85); }
  void ResetTone();
  void Tone(double gain, double offset, double gamma);
  void ToggleLabels();
  void ToggleLinks();
  void ToggleEpipolar();
  void BrushLarger();
  void BrushSmaller();
  void ShowShortcuts();
  // Help > Manual: docs/gui.md in a window of its own (kept open beside the work).
  void ShowManual();
  // The Fill Grid preview (G, Enter, Esc; see fill_grid_preview()).
  void BuildPreviewBanner();
  // from_corners: Find Path from the corners first (Ctrl+P), applied as its own step.
  void StartPreview(bool from_corners = false);
  void OnPreviewReady(Session::FillGridPreview preview);
  void AcceptPreview();
  void DiscardPreview() { DropPreview("discarded"); }
  // Forgets a pending or computing preview (nothing when there is none); the status bar then says
  // "Fill Grid preview <why>" ("discarded: the frame changed"), unless `why` is empty.
  void DropPreview(const QString& why);
  // Before the session is replaced or closed: the views' models let go and every worker that
  // reads it stopped (a tracking run too; it is window-modal, so normally there is none).
  void StopSessionWorkers();
  void ShowPreviewBanner();

  // Missing knots (the review queue's second kind) and hidden marks.
  void ConnectMissing();  // the review model and the timeline follow the session's list
  void OnMissingChanged();
  void HideSelected();         // D with no label selected: a hidden mark here
  void HideSelectedOnwards();  // Shift+D: here and in the following frames it is missing in

  // The knot picker's grid dock and its colour hint (I: which knot is the junction under the
  // cursor; the knots its colours fit are ringed in the grid until the frame or camera changes).
  void RefreshKnotGrid();
  void IdentifyAtCursor();
  void ClearHint();

  std::unique_ptr<Session> session_;
  std::unique_ptr<ReviewModel> review_model_;
  Cursor cursor_;
  std::unique_ptr<LabelingPresenter> presenter_;  // over session_, review_model_ and cursor_
  QSortFilterProxyModel* review_proxy_ = nullptr;
  QTableView* review_table_ = nullptr;
  QStackedWidget* stack_ = nullptr;
  QTabBar* rooms_ = nullptr;  // Recording, Calibration, Labeling (hidden on the welcome page)
  Room room_ = Room::kLabeling;
  RecordingRoom* recording_room_ = nullptr;
  CalibrationRoom* calibration_room_ = nullptr;
  ReconstructionRoom* reconstruction_room_ = nullptr;
  SimulationRoom* simulation_room_ = nullptr;
  std::vector<QAction*> labeling_actions_;  // enabled in the labeling room only
  std::vector<QWidget*> labeling_bars_;     // its docks and tool bar, hidden in the other rooms
  std::vector<bool> labeling_bars_shown_;   // ... whether each was shown (empty: they are out)
  QWidget* welcome_ = nullptr;
  QWidget* workspace_ = nullptr;
  QGridLayout* grid_ = nullptr;
  std::array<CameraView*, 4> views_{};
  Timeline* timeline_ = nullptr;
  QSpinBox* frame_box_ = nullptr;
  QSpinBox* row_box_ = nullptr;
  QSpinBox* col_box_ = nullptr;
  KnotGrid* knot_grid_ = nullptr;
  int cursor_camera_ = -1;  // the view and pixel the mouse was last over (I reads there)
  Eigen::Vector2d cursor_px_ = Eigen::Vector2d::Zero();
  int hint_camera_ = -1;  // the view of the grid's colour hint (-1: none shown)
  QLabel* status_frame_ = nullptr;
  QLabel* status_cursor_ = nullptr;
  QLabel* status_knot_ = nullptr;
  QTimer* play_timer_ = nullptr;
  std::vector<QAction*> actions_;
  QAction* advance_ = nullptr;  // Go > Advance to the frame's next review item after a fix
  QMenu* recent_menu_ = nullptr;

  int maximised_ = -1;
  bool half_ = false;
  bool show_labels_ = true, show_links_ = true, show_epipolar_ = true;
  double gain_ = 1.0, gamma_ = 1.0;
  // The background work, each the latest request only (declared after session_: destroyed
  // first, waiting for its worker).
  LatestRequest<Loaded> loader_{this, [this](Loaded loaded) { OnFrameLoaded(std::move(loaded)); }};
  bool frame_shown_ = false;
  std::vector<std::vector<Eigen::Vector2d>> candidates_;  // per camera, Find Node's several
  // The knot colours panel: what the selected label's yarns say against its code.
  QLabel* colours_label_ = nullptr;
  // Restarted by every change of frame, camera or knot: the check (a level-0 frame, decoded if
  // need be) runs once the person stops there, not for every frame scrubbed past.
  QTimer* colours_timer_ = nullptr;
  LatestRequest<std::optional<Session::KnotColours>> colours_{
      this, [this](std::optional<Session::KnotColours> c) { OnColoursRead(std::move(c)); }};
  // The tracking run on a worker.
  LatestRequest<Session::TrackRun> tracker_{
      this, [this](Session::TrackRun run) { OnTracked(std::move(run)); }};
  bool tracking_ = false;  // from the run's start until its result is applied
  QPointer<QProgressDialog> progress_;
  // The Fill Grid preview: its frame (-1: none wanted), whether it runs Find Path from the
  // corners first, the answer (a late answer of a dropped one never comes: LatestRequest).
  LatestRequest<Session::FillGridPreview> previewer_{
      this, [this](Session::FillGridPreview p) { OnPreviewReady(std::move(p)); }};
  int preview_frame_ = -1;
  // The recording room's presenter (over its own sequence of the project's experiment) and check.
  std::unique_ptr<RecordingPresenter> recording_;
  std::unique_ptr<CalibrationPresenter> calibration_;  // over session_'s rig
  // The simulation room's presenters, over session_ (the labels triangulated, the simulations).
  std::unique_ptr<ReconstructionPresenter> reconstruction_;
  std::unique_ptr<SimulationPresenter> simulation_;
  LatestRequest<recon::CheckReport> checker_{
      this, [this](recon::CheckReport report) { OnChecked(std::move(report)); }};
  bool preview_corners_ = false;
  std::optional<Session::FillGridPreview> preview_;
  QWidget* preview_banner_ = nullptr;
  QLabel* preview_text_ = nullptr;
  QAction* accept_preview_ = nullptr;   // enabled only while a preview is pending, so that
  QAction* discard_preview_ = nullptr;  // Enter and Esc keep their meaning elsewhere
};

}  // namespace netlab::gui
