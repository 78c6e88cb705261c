#include "app/gui/main_window.h"

#include <QAction>
#include <QApplication>
#include <QCloseEvent>
#include <QDateTime>
#include <QDialog>
#include <QDockWidget>
#include <QElapsedTimer>
#include <QFileDialog>
#include <QFileInfo>
#include <QFrame>
#include <QGridLayout>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QInputDialog>
#include <QKeyEvent>
#include <QLabel>
#include <QMenuBar>
#include <QMessageBox>
#include <QProgressDialog>
#include <QPushButton>
#include <QSortFilterProxyModel>
#include <QSpinBox>
#include <QStackedWidget>
#include <QStatusBar>
#include <QTabBar>
#include <QTableView>
#include <QTableWidget>
#include <QTextBrowser>
#include <QTextDocumentFragment>
#include <QTimer>
#include <QToolBar>
#include <QUndoStack>
#include <QVBoxLayout>
#include <QtConcurrent/QtConcurrent>
#include <algorithm>
#include <cmath>
#include <exception>

#include "app/gui/calibration_room.h"
#include "app/gui/camera_view.h"
#include "app/gui/knot_grid.h"
#include "app/gui/reconstruction_room.h"
#include "app/gui/recording_room.h"
#include "app/gui/settings.h"
#include "app/gui/shortcut_editor.h"
#include "app/gui/simulation_room.h"
#include "app/gui/timeline.h"

namespace netlab::gui {
namespace {

// Runs the event loop until done() or timeout_ms, sleeping between events: a loop that spun
// (processEvents with a time limit returns at once when nothing is pending) would take a whole
// core from the loader and the prefetch on a 2-core machine.
template <typename Done>
void WaitUntil(const Done& done, int timeout_ms) {
  QElapsedTimer timer;
  timer.start();
  QTimer tick;  // wakes the wait at least this often, to see the time limit
  tick.start(20);
  while (!done() && timer.elapsed() < timeout_ms)
    QCoreApplication::processEvents(QEventLoop::AllEvents | QEventLoop::WaitForMoreEvents);
  QCoreApplication::processEvents();
}

}  // namespace

MainWindow::MainWindow() {
  setWindowTitle("netlab");
  resize(1400, 980);
  auto* central = new QWidget(this);
  auto* central_layout = new QVBoxLayout(central);
  central_layout->setContentsMargins(0, 0, 0, 0);
  central_layout->setSpacing(0);
  rooms_ = new QTabBar;
  rooms_->setObjectName("rooms");
  central_layout->addWidget(rooms_);
  stack_ = new QStackedWidget;
  central_layout->addWidget(stack_, 1);
  setCentralWidget(central);
  BuildWelcome();
  BuildWorkspace();
  BuildActions();
  BuildPreviewBanner();
  BuildRooms();
  stack_->setCurrentWidget(welcome_);
  play_timer_ = new QTimer(this);
  play_timer_->setInterval(33);
  connect(play_timer_, &QTimer::timeout, this, [this] {
    if (frame() + 1 >= (session_ ? session_->frames() : 0))
      play_timer_->stop();
    else if (frame_shown_)
      SetFrame(frame() + 1);
  });
}

MainWindow::~MainWindow() {
  simulation_room_->Show(nullptr, nullptr);  // its frame loader reads the session
  tracker_.Cancel();
  tracker_.Wait();
  checker_.Wait();
  loader_.Wait();
  colours_.Wait();
  previewer_.Wait();
  review_table_->setModel(nullptr);
}

void MainWindow::BuildWelcome() {
  welcome_ = new QWidget;
  auto* layout = new QVBoxLayout(welcome_);
  auto* title = new QLabel(
      "<h2>netlab — knot labeling workstation</h2>"
      "<p>Open a project (project.yaml) or make one from an experiment, its "
      "rig and the net's colouring.</p>"
      "<p>New here? Help ▸ Manual walks through the workflow; F1 lists every key.</p>");
  title->setAlignment(Qt::AlignCenter);
  layout->addStretch();
  layout->addWidget(title);
  auto* buttons = new QHBoxLayout;
  auto* open = new QPushButton("Open project…");
  auto* create = new QPushButton("New project…");
  connect(open, &QPushButton::clicked, this, &MainWindow::OpenDialog);
  connect(create, &QPushButton::clicked, this, &MainWindow::NewProject);
  buttons->addStretch();
  buttons->addWidget(open);
  buttons->addWidget(create);
  buttons->addStretch();
  layout->addLayout(buttons);
  const QStringList recent = Settings::RecentProjects();
  if (!recent.isEmpty()) {
    layout->addWidget(new QLabel("<p align=center>Recent projects</p>"));
    for (const QString& path : recent) {
      auto* button = new QPushButton(path);
      button->setFlat(true);
      connect(button, &QPushButton::clicked, this, [this, path, button] {
        if (!OpenProject(path)) button->hide();  // and out of the settings' list
      });
      layout->addWidget(button);
    }
  }
  layout->addStretch();
  stack_->addWidget(welcome_);
}

void MainWindow::BuildWorkspace() {
  workspace_ = new QWidget;
  auto* layout = new QVBoxLayout(workspace_);
  layout->setContentsMargins(2, 2, 2, 2);
  grid_ = new QGridLayout;
  grid_->setSpacing(2);
  for (int c = 0; c < 4; ++c) {
    views_[c] = new CameraView(c);
    grid_->addWidget(views_[c], c / 2, c % 2);
    connect(views_[c], &CameraView::clicked, this, &MainWindow::OnClick);
    connect(views_[c], &CameraView::labelDragged, this, &MainWindow::OnDrag);
    connect(views_[c], &CameraView::labelSelected, this, &MainWindow::OnSelect);
    connect(views_[c], &CameraView::cursorMoved, this, &MainWindow::OnCursor);
    connect(views_[c], &CameraView::activated, this, &MainWindow::SetCamera);
  }
  layout->addLayout(grid_, 1);
  auto* bar = new QHBoxLayout;
  frame_box_ = new QSpinBox;
  frame_box_->setPrefix("frame ");
  frame_box_->setKeyboardTracking(false);
  frame_box_->setToolTip(
      "Click to type a frame number; Enter goes there and hands the keys back "
      "to the view");
  timeline_ = new Timeline;
  timeline_->setObjectName("labeling_timeline");
  bar->addWidget(frame_box_);
  bar->addWidget(timeline_, 1);
  layout->addLayout(bar);
  connect(timeline_, &Timeline::seek, this, &MainWindow::SetFrame);
  connect(frame_box_, &QSpinBox::valueChanged, this, [this](int f) {
    if (session_) SetFrame(f - session_->frame_number(0));
  });
  stack_->addWidget(workspace_);

  // The knot picker: which knot a click labels.
  auto* picker = addToolBar("Knot");
  picker->setObjectName("knot_toolbar");
  picker->addWidget(new QLabel(" Knot to label: row "));
  row_box_ = new QSpinBox;
  col_box_ = new QSpinBox;
  // Reached by a click only (never by the focus leaving a hidden view or by Tab), and taking only
  // a number's keys (eventFilter): the labeling keys are never typed into them.
  for (QSpinBox* box : {frame_box_, row_box_, col_box_}) {
    box->setFocusPolicy(Qt::ClickFocus);
    box->installEventFilter(this);
  }
  picker->addWidget(row_box_);
  picker->addWidget(new QLabel(" col "));
  picker->addWidget(col_box_);
  picker->addWidget(
      new QLabel("   click: Find Node in the brush · Shift+click: exactly here · "
                 "I: which knot is this? · drag a label: move it · 1-4 or a click on a "
                 "caption: the camera · F1: all keys"));
  auto picked = [this] {
    SetKnot(row_box_->value() * session_->project().cols + col_box_->value());
  };
  connect(row_box_, &QSpinBox::valueChanged, this, [this, picked] {
    if (session_) picked();
  });
  connect(col_box_, &QSpinBox::valueChanged, this, [this, picked] {
    if (session_) picked();
  });

  // The knot picker's grid: the knots and their labels in the current view; I rings the knots
  // the colours of the junction under the cursor fit.
  auto* grid_dock = new QDockWidget("Net grid: click the knot to label", this);
  grid_dock->setObjectName("knot_grid_dock");
  knot_grid_ = new KnotGrid;
  grid_dock->setWidget(knot_grid_);
  connect(knot_grid_, &KnotGrid::knotPicked, this, [this](int k) {
    SetKnot(k);
    statusBar()->showMessage(
        QString("Knot %1 picked: click it in a view to label it").arg(KnotName(k)), 4000);
  });

  // The review queue.
  auto* dock = new QDockWidget("Review queue", this);
  dock->setObjectName("review_dock");
  review_table_ = new QTableView;
  review_table_->setSelectionBehavior(QAbstractItemView::SelectRows);
  review_table_->setSelectionMode(QAbstractItemView::SingleSelection);
  review_table_->setSortingEnabled(true);
  review_table_->installEventFilter(this);
  review_table_->horizontalHeader()->setStretchLastSection(true);
  review_table_->verticalHeader()->setVisible(false);
  // One line per item: the Reason cut at its end ("…"), whole in the cell's tooltip and in the
  // status bar once the item is shown.
  review_table_->setWordWrap(false);
  // One line per item, as high as the text needs.
  review_table_->verticalHeader()->setDefaultSectionSize(review_table_->fontMetrics().height() + 8);
  review_table_->setTextElideMode(Qt::ElideRight);
  dock->setWidget(review_table_);
  dock->setMinimumWidth(480);
  addDockWidget(Qt::RightDockWidgetArea, dock);
  // The selected knot's colours: what its code expects, what the yarns say.
  auto* colours_dock = new QDockWidget("Knot colours", this);
  colours_dock->setObjectName("colours_dock");
  colours_label_ = new QLabel("Select a labeled knot to see its yarn colours.");
  colours_label_->setWordWrap(true);
  colours_label_->setTextFormat(Qt::RichText);
  colours_label_->setAlignment(Qt::AlignTop | Qt::AlignLeft);
  colours_label_->setMargin(6);
  colours_dock->setWidget(colours_label_);
  addDockWidget(Qt::RightDockWidgetArea, colours_dock);
  addDockWidget(Qt::RightDockWidgetArea, grid_dock);
  colours_timer_ = new QTimer(this);
  colours_timer_->setSingleShot(true);
  colours_timer_->setInterval(150);
  connect(colours_timer_, &QTimer::timeout, this, &MainWindow::RequestColours);
  connect(colours_dock, &QDockWidget::visibilityChanged, this, [this](bool visible) {
    if (visible) colours_timer_->start();
  });
  // A row double-clicked (or Enter on it): its item as Space shows it, the camera alone.
  connect(review_table_, &QTableView::activated, this, [this](const QModelIndex& index) {
    if (!review_model_ || !review_proxy_) return;
    const QModelIndex source = review_proxy_->mapToSource(index);
    if (source.isValid() && source.row() < review_model_->rowCount()) ShowReviewRow(source.row());
  });

  status_frame_ = new QLabel;
  status_cursor_ = new QLabel;
  status_knot_ = new QLabel;
  // The knot and the frame make room for a message (each view's caption says them too); the
  // cursor's pixel stays. A message longer than the bar is whole in the bar's tooltip.
  statusBar()->addWidget(status_knot_);
  statusBar()->addWidget(status_frame_, 1);
  status_frame_->setAlignment(Qt::AlignRight | Qt::AlignVCenter);
  statusBar()->addPermanentWidget(status_cursor_);
  // (QStatusBar hides them itself only when they are visible: not for a message given before
  // the window is shown, as the command line's --review does.)
  connect(statusBar(), &QStatusBar::messageChanged, this, [this](const QString& message) {
    statusBar()->setToolTip(message);
    status_knot_->setVisible(message.isEmpty());
    status_frame_->setVisible(message.isEmpty());
  });
}

QAction* MainWindow::AddAction(QMenu* menu, const QString& name, const QString& keys,
                               void (MainWindow::*slot)()) {
  auto* action = new QAction(name, this);
  action->setObjectName(name);  // the settings name and the default, for the shortcut editor
  action->setProperty(ShortcutEditor::kDefaultKeysProperty, keys);
  action->setShortcuts(Settings::Shortcuts(name, keys));
  action->setShortcutContext(Qt::WindowShortcut);
  connect(action, &QAction::triggered, this, slot);
  menu->addAction(action);
  addAction(action);
  actions_.push_back(action);
  return action;
}

void MainWindow::BuildActions() {
  QMenu* file = menuBar()->addMenu("&File");
  AddAction(file, "New project…", "Ctrl+N", &MainWindow::NewProject);
  AddAction(file, "Open project…", "Ctrl+O", &MainWindow::OpenDialog);
  AddAction(file, "Open recording (experiment.yaml)…", "Ctrl+Shift+O",
            &MainWindow::OpenRecordingDialog);
  recent_menu_ = file->addMenu("Open recent");
  connect(recent_menu_, &QMenu::aboutToShow, this, [this] {
    recent_menu_->clear();
    for (const QString& path : Settings::RecentProjects())
      recent_menu_->addAction(path, this, [this, path] { OpenProject(path); });
  });
  AddAction(file, "Save labels", "Ctrl+S", &MainWindow::Save);
  file->addSeparator();
  AddAction(file, "Quit", "Ctrl+Q", &MainWindow::Quit);

  const size_t first_labeling = actions_.size();
  QMenu* edit = menuBar()->addMenu("&Edit");
  AddAction(edit, "Undo", "Ctrl+Z", &MainWindow::Undo);
  AddAction(edit, "Redo", "Ctrl+Shift+Z;Ctrl+Y", &MainWindow::Redo);
  edit->addSeparator();
  QMenu* go = menuBar()->addMenu("&Go");
  AddAction(go, "Next frame", "F;Right", &MainWindow::NextFrame);
  AddAction(go, "Previous frame", "B;Left", &MainWindow::PreviousFrame);
  AddAction(go, "Forward 10 frames", "Shift+F;Shift+Right", &MainWindow::Forward10);
  AddAction(go, "Back 10 frames", "Shift+B;Shift+Left", &MainWindow::Back10);
  AddAction(go, "First frame", "Home", &MainWindow::FirstFrame);
  AddAction(go, "Last frame", "End", &MainWindow::LastFrame);
  AddAction(go, "Go to frame…", "Ctrl+G", &MainWindow::GoToFrame);
  AddAction(go, "Play / pause", "P", &MainWindow::TogglePlay);
  go->addSeparator();
  AddAction(go, "Next review item", "Space", &MainWindow::NextReviewItem);
  AddAction(go, "Previous review item", "Shift+Space", &MainWindow::PreviousReviewItem);
  AddAction(go, "First review item (earliest frame)", "Ctrl+Home", &MainWindow::FirstReviewItem);
  advance_ = go->addAction("Advance to the frame's next review item after a fix");
  advance_->setCheckable(true);
  advance_->setChecked(true);
  advance_->setToolTip(
      "After A, D, or a click that fixes a review item, go to the next item of the same frame");
  AddAction(go, "Camera 1 (current, shown alone when one is)", "1", &MainWindow::PickCamera1);
  AddAction(go, "Camera 2 (current, shown alone when one is)", "2", &MainWindow::PickCamera2);
  AddAction(go, "Camera 3 (current, shown alone when one is)", "3", &MainWindow::PickCamera3);
  AddAction(go, "Camera 4 (current, shown alone when one is)", "4", &MainWindow::PickCamera4);
  AddAction(go, "Next knot", ".", &MainWindow::NextKnot);
  AddAction(go, "Previous knot", ",", &MainWindow::PreviousKnot);

  AddAction(edit, "Accept label", "A", &MainWindow::AcceptSelected);
  AddAction(edit, "Delete label", "Delete;D", &MainWindow::DeleteSelected);
  AddAction(edit, "Mark hidden here and in the following frames", "Shift+D",
            &MainWindow::HideSelectedOnwards);
  AddAction(edit, "Nudge left 0.5 px", "Ctrl+Left", &MainWindow::NudgeLeft);
  AddAction(edit, "Nudge right 0.5 px", "Ctrl+Right", &MainWindow::NudgeRight);
  AddAction(edit, "Nudge up 0.5 px", "Ctrl+Up", &MainWindow::NudgeUp);
  AddAction(edit, "Nudge down 0.5 px", "Ctrl+Down", &MainWindow::NudgeDown);

  QMenu* tools = menuBar()->addMenu("&Tools");
  AddAction(tools, "Find Path from the corners", "Ctrl+P", &MainWindow::FindPathCorners);
  AddAction(tools, "Find Path to the previous knot", "Shift+P", &MainWindow::FindPathToPrevious);
  AddAction(tools, "Identify the knot under the cursor by its colours", "I",
            &MainWindow::IdentifyAtCursor);
  AddAction(tools, "Fill Grid in this frame", "G", &MainWindow::FillGridHere);
  // The preview's answers: enabled only while one is pending (BuildPreviewBanner).
  accept_preview_ =
      AddAction(tools, "Accept Fill Grid preview", "Return;Enter", &MainWindow::AcceptPreview);
  discard_preview_ = AddAction(tools, "Discard preview", "Esc", &MainWindow::DiscardPreview);
  AddAction(tools, "Track forwards", "T", &MainWindow::TrackForward);
  AddAction(tools, "Track backwards", "Shift+T", &MainWindow::TrackBackward);
  AddAction(tools, "Track to frame…", "Ctrl+T", &MainWindow::TrackToFrame);
  AddAction(tools, "Larger brush", "+;=", &MainWindow::BrushLarger);
  AddAction(tools, "Smaller brush", "-", &MainWindow::BrushSmaller);

  QMenu* view = menuBar()->addMenu("&View");
  AddAction(view, "Zoom every view on the knot", "Z", &MainWindow::ZoomOnKnot);
  AddAction(view, "Fit every view", "Ctrl+F", &MainWindow::FitAll);
  AddAction(view, "Maximise this camera / all cameras", "M", &MainWindow::ToggleMaximise);
  AddAction(view, "Half resolution", "H", &MainWindow::ToggleHalf);
  AddAction(view, "Brighter", "]", &MainWindow::Brighter);
  AddAction(view, "Darker", "[", &MainWindow::Darker);
  AddAction(view, "Gamma up (lift the darks)", "Shift+]", &MainWindow::GammaUp);
  AddAction(view, "Gamma down", "Shift+[", &MainWindow::GammaDown);
  AddAction(view, "Reset brightness", "\\", &MainWindow::ResetTone);
  AddAction(view, "Show labels", "L", &MainWindow::ToggleLabels);
  AddAction(view, "Show links", "K", &MainWindow::ToggleLinks);
  AddAction(view, "Show epipolar curves", "E", &MainWindow::ToggleEpipolar);
  // The panels: a closed one comes back from here (checked: shown).
  view->addSeparator();
  for (QDockWidget* dock : findChildren<QDockWidget*>()) view->addAction(dock->toggleViewAction());
  for (QToolBar* bar : findChildren<QToolBar*>()) view->addAction(bar->toggleViewAction());

  labeling_actions_.assign(actions_.begin() + static_cast<long>(first_labeling), actions_.end());
  QMenu* rooms = menuBar()->addMenu("&Room");
  AddAction(rooms, "Recording room", "Ctrl+1", &MainWindow::RecordingRoomAction);
  AddAction(rooms, "Calibration room", "Ctrl+2", &MainWindow::CalibrationRoomAction);
  AddAction(rooms, "Labeling room", "Ctrl+3", &MainWindow::LabelingRoomAction);
  AddAction(rooms, "Reconstruction room", "Ctrl+4", &MainWindow::ReconstructionRoomAction);
  AddAction(rooms, "Simulation room", "Ctrl+5", &MainWindow::SimulationRoomAction);
  QMenu* help = menuBar()->addMenu("&Help");
  AddAction(help, "Keyboard shortcuts", "F1;?", &MainWindow::ShowShortcuts);
  help->addAction("Manual (docs/gui.md)", this, &MainWindow::ShowManual);
}

bool MainWindow::OpenProject(const QString& path, bool ask, QString* error) {
  std::unique_ptr<Session> session;
  try {
    session = Session::Open(LoadProject(path.toStdString()));
  } catch (const std::exception& e) {
    Settings::RemoveRecentProject(QFileInfo(path).absoluteFilePath());
    const QString why = QString::fromLocal8Bit(e.what());
    if (error != nullptr)
      *error = why.contains(path) ? why : QString("%1: %2").arg(path, why);
    else
      QMessageBox::critical(this, "Cannot open the project", QString("%1\n\n%2").arg(path, why));
    return false;
  }
  if (!MaybeSave()) return false;
  // A journal left by a session that ended without saving: offer to recover it.
  const std::string labels = session->project().labels;
  if (LabelDocument::HasJournal(labels)) {
    const QString when = QFileInfo(QString::fromStdString(LabelDocument::JournalPath(labels)))
                             .lastModified()
                             .toString("yyyy-MM-dd hh:mm:ss");
    const auto answer =
        ask ? QMessageBox::question(this, "Recover unsaved edits?",
                                    QString("The last session on %1 ended without saving (its "
                                            "journal was last written %2). Recover its edits?")
                                        .arg(QString::fromStdString(labels), when),
                                    QMessageBox::Yes | QMessageBox::No, QMessageBox::Yes)
            : QMessageBox::No;
    try {
      if (answer == QMessageBox::Yes) {
        const int n = session->document().Recover();
        statusBar()->showMessage(QString("Recovered %1 labels from the journal").arg(n), 8000);
      } else if (ask) {
        session->document().DiscardJournal();
      }
    } catch (const std::exception& e) {
      QMessageBox::warning(this, "Cannot recover", QString::fromLocal8Bit(e.what()));
    }
  }
  StopSessionWorkers();
  session_ = std::move(session);
  review_model_ = std::make_unique<ReviewModel>(&session_->document(), session_->frame_numbers());
  const Project& p = session_->project();
  cursor_.Reset(session_->frames(), session_->cameras(), p.rows, p.cols);
  presenter_ = std::make_unique<LabelingPresenter>(session_.get(), review_model_.get(), &cursor_);
  review_proxy_ = new QSortFilterProxyModel(review_model_.get());
  review_proxy_->setSourceModel(review_model_.get());
  review_proxy_->setSortRole(Qt::EditRole);
  review_table_->setModel(review_proxy_);
  // Wide enough for the header and its sort arrow, and for the cells.
  for (int column : {ReviewModel::kCamera, ReviewModel::kFrame, ReviewModel::kKnot,
                     ReviewModel::kSource, ReviewModel::kSeverity})
    review_table_->resizeColumnToContents(column);
  connect(&session_->document(), &LabelDocument::labelsChanged, this, &MainWindow::OnLabelsChanged);
  connect(&session_->document(), &LabelDocument::journalFailed, this,
          [this](const QString& message) {
            QMessageBox::warning(this, "Edits are not journaled",
                                 message +
                                     "\n\nSave often (Ctrl+S), or make the labels' folder "
                                     "writable.");
          });
  connect(&session_->document(), &LabelDocument::modifiedChanged, this,
          [this](bool modified) { setWindowModified(modified); });
  setWindowTitle(QString("netlab — %1[*]").arg(QFileInfo(path).fileName()));
  setWindowModified(session_->document().modified());  // recovered edits are unsaved
  row_box_->setRange(0, p.rows - 1);
  col_box_->setRange(0, p.cols - 1);
  knot_grid_->SetNet(p.rows, p.cols);
  hint_camera_ = cursor_camera_ = -1;
  frame_box_->setRange(session_->frame_number(0), session_->frame_number(session_->frames() - 1));
  timeline_->SetRange(session_->frames());
  timeline_->SetReviewFrames(session_->document().ReviewFrames());
  ConnectMissing();
  for (int c = 0; c < 4; ++c) views_[c]->setVisible(c < session_->cameras());
  candidates_.assign(session_->cameras(), {});
  Settings::AddRecentProject(QFileInfo(path).absoluteFilePath());
  // The other rooms' presenters: the recording's check runs when its room is first shown.
  checker_.Drop();
  checker_.Wait();
  try {
    recording_ = std::make_unique<RecordingPresenter>(p.experiment);
  } catch (const std::exception& e) {
    recording_.reset();
    statusBar()->showMessage(
        QString("The recording room cannot open %1: %2")
            .arg(QString::fromStdString(p.experiment), QString::fromLocal8Bit(e.what())),
        10000);
  }
  calibration_ = std::make_unique<CalibrationPresenter>(&session_->rig(), p.rig, p.path);
  reconstruction_ = std::make_unique<ReconstructionPresenter>(session_.get());
  simulation_ = std::make_unique<SimulationPresenter>(session_.get(), reconstruction_.get());
  rooms_->show();
  for (int i = 0; i < rooms_->count(); ++i) rooms_->setTabEnabled(i, true);
  ShowRoom(Room::kLabeling);
  maximised_ = -1;  // the cursor shows no frame yet: SetFrame(0) loads it
  SetFrame(0);
  SetKnot(0);
  return true;
}

void MainWindow::SetFrame(int t) {
  if (!session_) return;
  int direction = 0;
  if (!cursor_.SetFrame(t, &direction)) return;
  t = cursor_.frame();
  DropPreview("discarded: the frame changed");
  for (auto& c : candidates_) c.clear();
  ClearHint();
  session_->cache().SetPlayhead(session_->frame_number(t), direction, half_ ? 1 : 0);
  {
    const QSignalBlocker block(frame_box_);
    frame_box_->setValue(session_->frame_number(t));
  }
  timeline_->SetCurrent(t);
  RequestFrame();  // the overlays follow with the image
  RefreshStatus();
  FocusView();
}

void MainWindow::FocusView() {
  if (!session_ || camera() < 0 || camera() >= session_->cameras() || camera() >= 4) return;
  // A spin box has the focus only when the person clicked into it: it keeps it until Enter or
  // Esc (its arrows step the frame). Anything else hands the keys to the view.
  if (qobject_cast<QAbstractSpinBox*>(QApplication::focusWidget()) != nullptr &&
      QApplication::focusWidget()->isVisible())
    return;
  if (views_[camera()]->isVisible() && !views_[camera()]->hasFocus())
    views_[camera()]->setFocus(Qt::OtherFocusReason);
}

bool MainWindow::eventFilter(QObject* watched, QEvent* event) {
  if (watched == review_table_ && event->type() == QEvent::ShortcutOverride) {
    // The queue's own keys (Home, End, the arrows, the pages, Enter) move in the queue as sorted
    // and show its item, not the window's frame shortcuts (Home: first frame); the labeling keys
    // (A, D, Space, ...) stay the window's.
    const auto* key = static_cast<QKeyEvent*>(event);
    const int k = key->key();
    if ((key->modifiers() & ~Qt::KeypadModifier) == Qt::NoModifier &&
        (k == Qt::Key_Home || k == Qt::Key_End || k == Qt::Key_Up || k == Qt::Key_Down ||
         k == Qt::Key_PageUp || k == Qt::Key_PageDown || k == Qt::Key_Return ||
         k == Qt::Key_Enter)) {
      event->accept();
      return true;
    }
    return QMainWindow::eventFilter(watched, event);
  }
  if (watched == review_table_ && event->type() == QEvent::KeyPress && review_table_->model()) {
    // Home and End: the queue's first and last item as sorted (a table's own Home and End move
    // along the row, and every column of a row is the same item).
    const auto* key = static_cast<QKeyEvent*>(event);
    const int rows = review_table_->model()->rowCount();
    if ((key->modifiers() & ~Qt::KeypadModifier) == Qt::NoModifier &&
        (key->key() == Qt::Key_Home || key->key() == Qt::Key_End) && rows > 0) {
      const int column = std::max(0, review_table_->currentIndex().column());
      review_table_->setCurrentIndex(
          review_table_->model()->index(key->key() == Qt::Key_Home ? 0 : rows - 1, column));
      return true;
    }
    return QMainWindow::eventFilter(watched, event);
  }
  auto* box = qobject_cast<QSpinBox*>(watched);
  if (box == nullptr ||
      (event->type() != QEvent::ShortcutOverride && event->type() != QEvent::KeyPress))
    return QMainWindow::eventFilter(watched, event);
  const auto* key = static_cast<QKeyEvent*>(event);
  const Qt::KeyboardModifiers mods = key->modifiers() & ~Qt::KeypadModifier;
  const int k = key->key();
  const bool enter = k == Qt::Key_Return || k == Qt::Key_Enter, escape = k == Qt::Key_Escape;
  // A number's keys: digits, editing, the steps (the arrows), Enter and Esc.
  const bool number =
      mods == Qt::NoModifier &&
      ((k >= Qt::Key_0 && k <= Qt::Key_9) || k == Qt::Key_Backspace || k == Qt::Key_Delete ||
       k == Qt::Key_Left || k == Qt::Key_Right || k == Qt::Key_Up || k == Qt::Key_Down ||
       k == Qt::Key_PageUp || k == Qt::Key_PageDown || k == Qt::Key_Home || k == Qt::Key_End ||
       enter || escape);
  if (event->type() == QEvent::ShortcutOverride) {
    if (number) {
      event->accept();  // the box's, not the window's (Enter would accept a preview)
    } else {
      event->ignore();  // the window's shortcut (A, D, T, Space, Ctrl+S, ...)
    }
    return true;
  }
  if (escape) {  // the typed text forgotten, the keys back to the view
    if (session_) {
      const QSignalBlocker block(box);
      const int cols = session_->project().cols;
      box->setValue(box == frame_box_ ? session_->frame_number(frame())
                    : box == row_box_ ? knot() / cols
                                      : knot() % cols);
    }
    box->clearFocus();
    FocusView();
    return true;
  }
  if (enter) {  // the box takes the number, then the keys go back to the view
    QTimer::singleShot(0, this, [this, box] {
      if (box->hasFocus()) box->clearFocus();
      FocusView();
    });
  }
  return false;
}

void MainWindow::RequestFrame() {
  // Decoded, reduced to each view's size and toned off the GUI thread; a newer request makes this
  // one's answer stale.
  frame_shown_ = false;
  const int t = frame(), level = half_ ? 1 : 0;
  Session* session = session_.get();
  std::array<double, 4> fit{};  // screen pixels per full-resolution pixel, per view
  for (int c = 0; c < session->cameras() && c < 4; ++c)
    fit[c] = views_[c]->FitScreenPerImage(session->rig_camera(c).intrinsics.width);
  const cv::Mat tone = ToneTable(gain_, 0, gamma_);
  loader_.Request([session, t, level, fit, tone](const CancelToken&) {
    Loaded loaded;
    loaded.t = t;
    for (int c = 0; c < session->cameras() && c < 4; ++c) {
      std::string error;
      const auto image = session->cache().Get(c, session->frame_number(t), level, &error);
      if (image) {
        const double full_width = session->rig_camera(c).intrinsics.width;
        loaded.frames[c] = MakeViewFrame(*image, fit[c] * full_width / image->cols, tone);
      } else {
        loaded.problems[c] = QString("frame %1 cannot be read:\n%2")
                                 .arg(session->frame_number(t))
                                 .arg(QString::fromStdString(error));
      }
    }
    return loaded;
  });
}

void MainWindow::OnFrameLoaded(Loaded loaded) {
  if (!session_) return;
  for (int c = 0; c < session_->cameras() && c < 4; ++c) {
    const calib::CameraIntrinsics& in = session_->rig_camera(c).intrinsics;
    views_[c]->SetFrame(std::move(loaded.frames[c]), in.width, in.height, loaded.problems[c]);
  }
  // The frame's labels with its image, in the same paint: never one frame's labels over another
  // frame's image.
  frame_shown_ = true;
  RefreshOverlays();
}

bool MainWindow::WaitForFrame(int timeout_ms) {
  WaitUntil([this] { return frame_shown_; }, timeout_ms);
  return frame_shown_;
}

void MainWindow::RefreshOverlays() {
  // While a frame loads, the views keep the last frame's image and labels (OnFrameLoaded draws
  // the new ones together).
  if (!session_ || frame() < 0 || !frame_shown_) return;
  for (int c = 0; c < session_->cameras() && c < 4; ++c)
    views_[c]->SetOverlay(presenter_->Overlay(c, candidates_[c], fill_grid_preview()));
  RefreshKnotGrid();
}

void MainWindow::RefreshKnotGrid() {
  if (!session_ || frame() < 0) return;
  const LabelDocument& doc = session_->document();
  std::vector<KnotGrid::Cell> cells(session_->project().knots());
  for (int k = 0; k < static_cast<int>(cells.size()); ++k) {
    const recon::Label& l = doc.at(camera(), frame(), k);
    if (l.state == recon::LabelState::kHidden)
      cells[k].hidden = true;
    else if (l.present())
      cells[k].label = LabelColour(l);
  }
  knot_grid_->SetCells(std::move(cells));
  knot_grid_->SetSelected(knot());
  QString source;  // the simulation room's score, per knot
  std::vector<double> errors;
  if (simulation_) errors = simulation_->ShownKnotErrorsMm(&source);
  knot_grid_->SetErrors(std::move(errors), source);
}

void MainWindow::ClearHint() {
  if (hint_camera_ < 0) return;
  hint_camera_ = -1;
  knot_grid_->SetOffered({}, false);
}

void MainWindow::IdentifyAtCursor() {
  if (!session_ || busy()) return;
  if (cursor_camera_ < 0 || cursor_camera_ >= session_->cameras()) {
    statusBar()->showMessage("Identify: point the brush at a junction in a view, then press I",
                             6000);
    return;
  }
  const int c = cursor_camera_;
  SetCamera(c);
  const Session::JunctionHint hint =
      session_->IdentifyJunction(c, frame(), cursor_px_, views_[c]->brush_radius());
  const bool identified = hint.reading.status == recon::IdentifyStatus::kIdentified;
  knot_grid_->SetOffered(hint.reading.knots, identified);
  hint_camera_ = c;
  const QString why = QString::fromStdString(hint.reading.why);
  QString message;
  if (!hint.found) {
    message = "Identify: " + why;
  } else if (identified) {
    SetKnot(hint.reading.knots.front());
    message =
        QString("Identify: the colours say knot %1 (picked; click the junction to label it) — %2")
            .arg(KnotName(knot()), why);
  } else if (!hint.reading.knots.empty()) {
    message = QString("Identify: %1 knots possible, ringed in the Net grid: pick one there — %2")
                  .arg(hint.reading.knots.size())
                  .arg(why);
  } else {
    message = "Identify: the colours fit no free knot — " + why;
  }
  statusBar()->showMessage(message, 15000);
}

void MainWindow::RefreshStatus() {
  // The status bar speaks of the room shown: the labeling room's frame, camera and knot; the
  // reconstruction and simulation rooms' own slider's frame; no frame in the other rooms.
  if (room_ != Room::kLabeling) {
    status_knot_->clear();
    status_cursor_->clear();
    status_frame_->setText(room_ == Room::kReconstruction ? reconstruction_room_->FrameStatus()
                           : room_ == Room::kSimulation   ? simulation_room_->FrameStatus()
                                                          : QString());
    return;
  }
  if (!session_ || frame() < 0) return;
  status_frame_->setText(presenter_->FrameStatus());
  status_knot_->setText(presenter_->KnotStatus());
  ShowColours();
}

void MainWindow::ShowColours() {
  if (!session_ || frame() < 0) return;
  // At once the knot as selected, its expected colours (also for a knot with no label, as a
  // missing knot of the queue); what its yarns say follows (RequestColours).
  colours_.Drop();
  colours_label_->setText(presenter_->ColoursText(session_->ExpectedColours(knot())));
  if (session_->document().at(camera(), frame(), knot()).present()) colours_timer_->start();
}

void MainWindow::RequestColours() {
  if (!session_ || frame() < 0 || !colours_label_->isVisible()) return;
  const int c = camera(), t = frame(), k = knot();
  const recon::Label& label = session_->document().at(c, t, k);
  if (!label.present()) return;
  const Session* session = session_.get();
  const Eigen::Vector2d px = label.px;
  const recon::YarnDirections yarns =
      recon::AcceptedNeighbourYarns(session_->document().labels(), c, t, k);
  colours_.Request([session, c, t, k, px, yarns](const CancelToken&) {
    return session->CheckKnotColours(c, t, k, px, yarns);
  });
}

void MainWindow::OnColoursRead(std::optional<Session::KnotColours> colours) {
  if (session_) colours_label_->setText(presenter_->ColoursText(colours));
}

void MainWindow::OnLabelsChanged(const QList<int>& frames) {
  DropPreview("discarded: the labels changed");
  // The tracks of those frames follow the labels (the current frame's first).
  if (reconstruction_ && reconstruction_->tracks() != nullptr) {
    std::vector<int> rows(frames.begin(), frames.end());
    std::stable_partition(rows.begin(), rows.end(), [this](int t) { return t == frame(); });
    reconstruction_->UpdateRows(rows);
  }
  timeline_->SetReviewFrames(session_->document().ReviewFrames());
  if (frames.contains(frame())) {
    RefreshOverlays();
    RefreshStatus();
  }
}

QString MainWindow::KnotName(int knot) const {
  return session_ ? cursor_.KnotName(knot) : QString();
}

void MainWindow::SetCamera(int c) {
  if (!session_ || c < 0 || c >= session_->cameras()) return;
  if (c != hint_camera_) ClearHint();
  cursor_.SetCamera(c);
  // One camera shown alone: the camera acted on is the one shown.
  if (maximised_ >= 0 && maximised_ != c) Maximise(c);
  RefreshKnotGrid();
  RefreshStatus();
  FocusView();
}

void MainWindow::SetKnot(int knot) {
  if (!session_) return;
  cursor_.SetKnot(knot);
  knot = cursor_.knot();
  {
    const QSignalBlocker a(row_box_), b(col_box_);
    row_box_->setValue(knot / session_->project().cols);
    col_box_->setValue(knot % session_->project().cols);
  }
  knot_grid_->SetSelected(knot);
  RefreshOverlays();
  RefreshStatus();
}

void MainWindow::OnClick(int camera, const Eigen::Vector2d& px, Qt::KeyboardModifiers modifiers) {
  if (!session_ || busy()) return;
  SetCamera(camera);
  const LabelKey key{camera, frame(), knot()};
  const bool was_review = InQueue(camera, frame(), knot());  // a review item or a missing knot
  if (modifiers & Qt::ShiftModifier) {  // exactly where clicked: the person's own label
    session_->PlaceLabel(camera, frame(), knot(), px, "Place " + KnotName(knot()).toStdString());
    statusBar()->showMessage(QString("Placed knot %1 by hand").arg(KnotName(knot())), 4000);
    AdvanceAfterFix(key, was_review);
    return;
  }
  const recon::FindNodeResult r =
      session_->FindNode(camera, frame(), knot(), px, views_[camera]->brush_radius());
  candidates_[camera].clear();
  const int timeout = r.status == recon::FindNodeStatus::kFound ? 6000 : 8000;
  statusBar()->showMessage(presenter_->FindNodeMessage(camera, r), timeout);
  if (r.status == recon::FindNodeStatus::kFound) {
    if (!presenter_->walk().UnderReview(camera, frame(), knot())) AdvanceAfterFix(key, was_review);
  } else if (r.status == recon::FindNodeStatus::kSeveral) {
    for (const recon::Junction& j : r.candidates) candidates_[camera].push_back(j.px);
    RefreshOverlays();
  }
}

void MainWindow::OnDrag(int camera, int knot, const Eigen::Vector2d& px) {
  if (!session_ || busy()) return;
  session_->PlaceLabel(camera, frame(), knot, px, "Move " + KnotName(knot).toStdString());
}

void MainWindow::OnSelect(int camera, int knot) {
  SetCamera(camera);
  SetKnot(knot);
}

void MainWindow::OnCursor(int camera, const Eigen::Vector2d& px, const QString& value) {
  cursor_camera_ = camera;
  cursor_px_ = px;
  status_cursor_->setText(
      QString("%1 · x %2 y %3 %4")
          .arg(QString::fromStdString(session_ ? session_->camera_names()[camera] : ""))
          .arg(px.x(), 0, 'f', 1)
          .arg(px.y(), 0, 'f', 1)
          .arg(value));
}

// ---------------------------------------------------------------------------------------------
// Actions.

void MainWindow::NewProject() {
  // Each dialog's title says what it asks (the steps depend on the answers: no count to
  // contradict).
  const QString experiment = QFileDialog::getOpenFileName(
      this, "New project: the experiment (experiment.yaml)", {}, "Experiment (*.yaml)");
  if (experiment.isEmpty()) return;
  const QString rig = QFileDialog::getOpenFileName(this, "New project: the calibrated rig",
                                                   QFileInfo(experiment).path(), "Rig (*.yaml)");
  if (rig.isEmpty()) return;
  const QString coloring = QFileDialog::getOpenFileName(
      this, "New project: the net's colouring, coloring.yaml (Cancel: none)", QFileInfo(rig).path(),
      "Colouring (*.yaml)");
  // The target, so that the knots it hides are not listed missing (a scenario's or a netlab
  // simulate result's bodies, in the rig's world frame).
  const QString target = QFileDialog::getOpenFileName(
      this,
      "New project: the target, so that the knots it hides are not listed missing: its scenario "
      "or simulation (Cancel: none)",
      QFileInfo(experiment).path(), "Scenario or simulation (*.yaml *.h5)");
  int rows = 0, cols = 0;
  if (coloring.isEmpty()) {  // the grid from the person: rows and columns (Net B is 17 x 17)
    bool ok = false;
    rows = QInputDialog::getInt(this, "New project: the net", "Knots in a column (rows):", 11, 2,
                                1000, 1, &ok);
    if (!ok) return;
    cols = QInputDialog::getInt(this, "New project: the net", "Knots in a row (columns):", rows, 2,
                                1000, 1, &ok);
    if (!ok) return;
  }
  const auto balls = QMessageBox::question(
      this, "New project: the net",
      "Has the net knot balls?\n\nNo: a knotless net (Net B), whose edge knots must lie where "
      "the colour of their straight links changes.",
      QMessageBox::Yes | QMessageBox::No | QMessageBox::Cancel, QMessageBox::Yes);
  if (balls == QMessageBox::Cancel) return;
  const QString labels = QFileDialog::getSaveFileName(
      this, "New project: where the labels are saved", QFileInfo(experiment).path() + "/labels.h5",
      "Labels (*.h5)", nullptr, QFileDialog::DontConfirmOverwrite);
  if (labels.isEmpty()) return;
  const QString path =
      QFileDialog::getSaveFileName(this, "New project: save the project as",
                                   QFileInfo(labels).path() + "/project.yaml", "Project (*.yaml)");
  if (path.isEmpty()) return;
  try {
    Project project = MakeProject(experiment.toStdString(), rig.toStdString(),
                                  coloring.toStdString(), labels.toStdString(), rows, cols);
    project.knotless = balls == QMessageBox::No;
    if (!target.isEmpty()) {
      LoadTarget(target.toStdString(), 179.0);  // refused here, naming the file, if unreadable
      project.target = target.toStdString();
    }
    SaveProject(project, path.toStdString());
  } catch (const std::exception& e) {
    QMessageBox::critical(this, "Cannot make the project", QString::fromLocal8Bit(e.what()));
    return;
  }
  OpenProject(path);
}

void MainWindow::OpenDialog() {
  const QString path =
      QFileDialog::getOpenFileName(this, "Open a project", {}, "netlab project (*.yaml)");
  if (!path.isEmpty()) OpenProject(path);
}

void MainWindow::Save() {
  if (!session_) return;
  try {
    session_->document().Save();
    statusBar()->showMessage(
        QString("Saved %1").arg(QString::fromStdString(session_->document().labels_path())), 4000);
  } catch (const std::exception& e) {
    QMessageBox::critical(this, "Cannot save the labels",
                          QString("%1\n\nThe file on disk is unchanged; your edits are kept in "
                                  "the journal.")
                              .arg(QString::fromLocal8Bit(e.what())));
  }
}

void MainWindow::Undo() {
  if (session_ && !busy()) session_->document().undo_stack()->undo();
}

void MainWindow::Redo() {
  if (session_ && !busy()) session_->document().undo_stack()->redo();
}

void MainWindow::LastFrame() {
  if (session_) SetFrame(session_->frames() - 1);
}

void MainWindow::GoToFrame() {
  if (!session_) return;
  bool ok = false;
  const int f = QInputDialog::getInt(
      this, "Go to frame", "Frame number:", session_->frame_number(frame()),
      session_->frame_number(0), session_->frame_number(session_->frames() - 1), 1, &ok);
  if (ok) SetFrame(f - session_->frame_number(0));
}

void MainWindow::TogglePlay() {
  if (play_timer_->isActive())
    play_timer_->stop();
  else
    play_timer_->start();
}

void MainWindow::NextReview(bool backwards) {
  const int row =
      presenter_ ? presenter_->walk().NextRow({camera(), frame(), knot()}, backwards) : -1;
  if (row < 0) {
    statusBar()->showMessage("Nothing to review", 3000);
    return;
  }
  ShowReviewRow(row);
}

void MainWindow::FirstReviewItem() {
  if (!session_ || !review_model_ || review_model_->rowCount() == 0) {
    statusBar()->showMessage("Nothing to review", 3000);
    return;
  }
  ShowReviewRow(0);
}

void MainWindow::ShowReviewRow(int row) {
  const auto [c, t, k] = review_model_->items()[row];
  presenter_->walk().TookTo(row);
  SetFrame(t);
  SetCamera(c);
  SetKnot(k);
  if (maximised_ != c) Maximise(c);
  ZoomOnKnot();
  const QModelIndex index = review_proxy_->mapFromSource(review_model_->index(row, 0));
  review_table_->selectRow(index.row());
  statusBar()->showMessage(presenter_->ReviewMessage(row),
                           review_model_->IsMissing(row) ? 15000 : 10000);
}

void MainWindow::AcceptSelected() {
  if (!session_ || busy()) return;
  const int c = camera(), t = frame(), k = knot();
  const bool was_review = InQueue(c, t, k);
  session_->AcceptLabel(c, t, k);
  AdvanceAfterFix({c, t, k}, was_review);
}

void MainWindow::DeleteSelected() {
  if (!session_ || busy()) return;
  const int c = camera(), t = frame(), k = knot();
  const bool was_queued = InQueue(c, t, k);
  if (!session_->document().at(c, t, k).present())
    HideSelected();  // no label here: the person says the knot is not visible
  else
    session_->DeleteLabel(c, t, k);
  AdvanceAfterFix({c, t, k}, was_queued);
}

bool MainWindow::InQueue(int camera, int t, int knot) const {
  return presenter_->walk().InQueue(camera, t, knot);
}

void MainWindow::AdvanceAfterFix(const LabelKey& key, bool was_queued) {
  if (!advance_->isChecked()) return;
  const int row = presenter_->walk().AdvanceRow(key, was_queued);
  if (row >= 0) ShowReviewRow(row);
}

void MainWindow::Nudge(double dx, double dy) {
  if (!session_ || busy()) return;
  const recon::Label& l = session_->document().at(camera(), frame(), knot());
  if (!l.present()) return;
  // Half a pixel when a pixel is a screen pixel or larger; scaled up when zoomed out, so a nudge
  // is always visible.
  const double factor = std::max(1.0, 1.0 / std::max(views_[camera()]->scale(), 1e-3));
  session_->PlaceLabel(camera(), frame(), knot(), l.px + Eigen::Vector2d(dx, dy) * factor,
                       "Nudge " + KnotName(knot()).toStdString());
}

void MainWindow::FindPathCorners() {
  // On a worker, shown as a preview like G's: Enter applies it (two undo steps), Esc discards.
  if (session_ && !busy()) StartPreview(true);
}

void MainWindow::FindPathToPrevious() {
  if (!session_ || busy() || cursor_.previous_knot() < 0) return;
  const std::string why =
      session_->FindPathBetween(camera(), frame(), cursor_.previous_knot(), knot());
  statusBar()->showMessage(why.empty()
                               ? QString("Find Path %1 → %2: done")
                                     .arg(KnotName(cursor_.previous_knot()), KnotName(knot()))
                               : "Find Path refused: " + QString::fromStdString(why),
                           8000);
}

void MainWindow::FillGridHere() {
  // A preview first (OnPreviewReady shows it; Enter applies it).
  if (session_ && !busy()) StartPreview();
}

void MainWindow::TrackForward() {
  if (session_) TrackTo(session_->frames() - 1);
}
void MainWindow::TrackBackward() { TrackTo(0); }

void MainWindow::TrackToFrame() {
  if (!session_) return;
  bool ok = false;
  const int f = QInputDialog::getInt(
      this, "Track to frame", "Track up to frame number:",
      session_->frame_number(std::min(frame() + 30, session_->frames() - 1)),
      session_->frame_number(0), session_->frame_number(session_->frames() - 1), 1, &ok);
  if (ok) TrackTo(f - session_->frame_number(0), false, -1);  // the range asked for, in one run
}

void MainWindow::TrackTo(int to, bool wait, int max_review) {
  if (!session_ || busy() || to == frame()) return;
  DropPreview("discarded: a tracking run started");
  // A snapshot on the GUI thread; the run never touches the document.
  const int from = frame();
  auto* progress = new QProgressDialog(QString("Tracking from frame %1 to %2 …")
                                           .arg(session_->frame_number(from))
                                           .arg(session_->frame_number(to)),
                                       "Cancel", 0, std::abs(to - from), this);
  progress->setWindowModality(Qt::WindowModal);
  progress->setMinimumDuration(300);
  progress->setAttribute(Qt::WA_DeleteOnClose);
  connect(progress, &QProgressDialog::canceled, this, [this] { tracker_.Cancel(); });
  progress_ = progress;
  const Session* session = session_.get();
  QPointer<QProgressDialog> bar(progress);
  auto report = [this, bar](const Progress& p) {
    const int done = static_cast<int>(p.done);
    QMetaObject::invokeMethod(
        this,
        [bar, done] {
          if (bar) bar->setValue(done);
        },
        Qt::QueuedConnection);
  };
  tracking_ = true;
  tracker_.Request([session, snapshot = session_->document().labels(), from, to, report,
                    max_review](const CancelToken& cancel) {
    return session->Track(snapshot, from, to, ProgressReporter(report, cancel), max_review);
  });
  if (wait) {
    while (busy()) QCoreApplication::processEvents(QEventLoop::AllEvents, 20);
    QCoreApplication::processEvents();
  }
}

void MainWindow::OnTracked(Session::TrackRun run) {
  tracking_ = false;
  if (progress_) progress_->close();
  // The closed progress dialog may leave no window active (Qt's offscreen platform does):
  // the keys would go nowhere.
  activateWindow();
  if (QApplication::activeWindow() != this) QApplication::setActiveWindow(this);
  if (!session_) return;
  const int changed = session_->ApplyTrackRun(run);
  statusBar()->showMessage(TrackMessage(run, session_->frame_number(run.last_done), changed),
                           10000);
  SetFrame(run.last_done);
  // Stopped where the person is needed: that frame's first label for review (what stopped
  // the run; the frame's missing knots wait, as after a fix), else its first item.
  if (run.stopped_for_review) {
    const int row = presenter_->walk().StopRow(run.last_done);
    if (row >= 0) ShowReviewRow(row);
  }
}

void MainWindow::ZoomOnKnot() {
  if (!session_) return;
  // Every view onto the knot: its label, else its reprojected point.
  const recon::PointEstimate point = session_->Triangulate(frame(), knot());
  for (int c = 0; c < session_->cameras(); ++c) {
    const recon::Label& l = session_->document().at(c, frame(), knot());
    if (l.present())
      views_[c]->ZoomTo(l.px, 80);
    else if (point.valid)
      views_[c]->ZoomTo(session_->rig_camera(c).ProjectWorld(point.position), 80);
  }
}

void MainWindow::FitAll() {
  for (CameraView* v : views_) v->Fit();
}

void MainWindow::SetHalfResolution(bool half) {
  half_ = half;
  if (session_) {
    session_->cache().SetPlayhead(session_->frame_number(frame()), 0, half_ ? 1 : 0);
    RequestFrame();
  }
  statusBar()->showMessage(half_ ? "Half resolution" : "Full resolution", 2000);
}

void MainWindow::Maximise(int c) {
  maximised_ = c;
  // The view to be shown first: hiding the one with the focus then moves it there, not away.
  if (session_ && c >= 0 && c < session_->cameras() && c < 4) views_[c]->setVisible(true);
  for (int i = 0; i < 4; ++i)
    views_[i]->setVisible(session_ && i < session_->cameras() && (c < 0 || i == c));
  FocusView();
}

void MainWindow::ToggleMaximise() { Maximise(maximised_ >= 0 ? -1 : camera()); }

void MainWindow::Tone(double gain, double offset, double gamma) {
  gain_ *= gain;
  gamma_ *= gamma;
  for (CameraView* v : views_) v->SetTone(gain_, offset, gamma_);
}

void MainWindow::ResetTone() {
  gain_ = gamma_ = 1.0;
  Tone(1, 0, 1);
}

void MainWindow::ToggleLabels() {
  show_labels_ = !show_labels_;
  for (CameraView* v : views_) v->SetShowLabels(show_labels_);
}

void MainWindow::ToggleLinks() {
  show_links_ = !show_links_;
  for (CameraView* v : views_) v->SetShowLinks(show_links_);
}

void MainWindow::ToggleEpipolar() {
  show_epipolar_ = !show_epipolar_;
  for (CameraView* v : views_) v->SetShowEpipolar(show_epipolar_);
}

void MainWindow::BrushLarger() {
  for (CameraView* v : views_) v->SetBrushRadius(std::min(60.0, v->brush_radius() * 1.25));
}

void MainWindow::BrushSmaller() {
  for (CameraView* v : views_) v->SetBrushRadius(std::max(2.0, v->brush_radius() / 1.25));
}

void MainWindow::ShowShortcuts() {
  QDialog dialog(this);
  dialog.setWindowTitle("Keyboard shortcuts");
  auto* layout = new QVBoxLayout(&dialog);
  auto* table = new QTableWidget(static_cast<int>(actions_.size()) + 4, 2);
  table->setHorizontalHeaderLabels({"Action", "Keys"});
  const auto fill_keys = [&] {  // the actions' rows (again after the editor changed them)
    int row = 0;
    for (QAction* a : actions_) {
      QStringList keys;
      for (const QKeySequence& k : a->shortcuts()) keys << k.toString(QKeySequence::NativeText);
      table->setItem(row, 0, new QTableWidgetItem(a->text()));
      table->setItem(row++, 1, new QTableWidgetItem(keys.join("  or  ")));
    }
  };
  fill_keys();
  int row = static_cast<int>(actions_.size());
  const std::pair<const char*, const char*> mouse[] = {
      {"Find Node at the brush (the knot to label)", "click"},
      {"Place the label exactly", "Shift+click"},
      {"Select / move a label", "click / drag it"},
      {"Zoom at the cursor · pan · brush size", "wheel · middle or right drag · Ctrl+wheel"}};
  for (const auto& [what, how] : mouse) {
    table->setItem(row, 0, new QTableWidgetItem(what));
    table->setItem(row++, 1, new QTableWidgetItem(how));
  }
  table->horizontalHeader()->setStretchLastSection(true);
  table->verticalHeader()->setVisible(false);
  table->resizeColumnsToContents();
  table->setEditTriggers(QAbstractItemView::NoEditTriggers);
  auto* change = new QPushButton("Change shortcuts…");
  connect(change, &QPushButton::clicked, &dialog, [&] {
    ShortcutEditor editor(actions_, &dialog);
    if (editor.exec() != QDialog::Accepted) return;
    fill_keys();
    table->resizeColumnsToContents();
  });
  auto* top = new QHBoxLayout;
  top->addWidget(new QLabel("Change any key with “Change shortcuts…”; yours are kept in the "
                            "settings (netlab-gui)."),
                 1);
  top->addWidget(change);
  layout->addLayout(top);
  layout->addWidget(table);
  dialog.resize(620, 700);
  dialog.exec();
}

void MainWindow::ShowManual() {
  // The source tree's docs (where netlab is built), else a docs folder beside the executable.
  QString docs;
  for (const QString& dir :
       {QStringLiteral(NETLAB_DOCS_DIR), QCoreApplication::applicationDirPath() + "/../docs",
        QCoreApplication::applicationDirPath() + "/../../docs"})
    if (QFileInfo::exists(dir + "/gui.md")) {
      docs = QFileInfo(dir).canonicalFilePath();
      break;
    }
  if (docs.isEmpty()) {
    QMessageBox::information(this, "Manual",
                             "The manual is docs/gui.md in netlab's source tree (not found "
                             "from here: " NETLAB_DOCS_DIR ").");
    return;
  }
  auto* manual = findChild<QDialog*>("manual");
  if (manual == nullptr) {
    manual = new QDialog(this);
    manual->setObjectName("manual");
    manual->setWindowTitle("netlab gui — manual (" + docs + "/gui.md)");
    auto* layout = new QVBoxLayout(manual);
    auto* browser = new QTextBrowser;
    browser->setOpenExternalLinks(true);
    browser->setSearchPaths({docs});
    browser->setSource(QUrl::fromLocalFile(docs + "/gui.md"), QTextDocument::MarkdownResource);
    layout->addWidget(browser);
    manual->resize(900, 900);
  }
  manual->show();
  manual->raise();
}

bool MainWindow::MaybeSave() {
  if (!session_ || !session_->document().modified()) return true;
  const auto answer = QMessageBox::question(
      this, "Unsaved labels", "The labels have unsaved edits. Save them?",
      QMessageBox::Save | QMessageBox::Discard | QMessageBox::Cancel, QMessageBox::Save);
  if (answer == QMessageBox::Cancel) return false;
  if (answer == QMessageBox::Save) {
    Save();
    return !session_->document().modified();
  }
  session_->document().DiscardJournal();
  return true;
}

void MainWindow::closeEvent(QCloseEvent* event) {
  if (MaybeSave())
    event->accept();
  else
    event->ignore();
}

// ---------------------------------------------------------------------------------------------
// Missing knots (the review queue's second kind) and hidden marks.

void MainWindow::ConnectMissing() {
  review_model_->SetMissing(&session_->missing());
  connect(&session_->missing(), &MissingKnots::changed, this, &MainWindow::OnMissingChanged);
  OnMissingChanged();
}

void MainWindow::OnMissingChanged() { timeline_->SetMissingFrames(session_->missing().Frames()); }

void MainWindow::HideSelected() {
  if (!session_ || busy()) return;
  const QString where = presenter_->Where();
  if (session_->document().at(camera(), frame(), knot()).hidden()) {
    statusBar()->showMessage(where + " is already marked hidden; a click labels it", 6000);
    return;
  }
  session_->MarkHidden(camera(), frame(), knot());
  statusBar()->showMessage(
      "Marked " + where + " hidden: the tools will not label it there (Ctrl+Z undoes)", 8000);
}

void MainWindow::HideSelectedOnwards() {
  if (!session_ || busy()) return;
  if (!session_->missing().Find(camera(), frame(), knot())) {
    statusBar()->showMessage(
        QString("Shift+D marks a missing knot hidden through the frames it is missing in; knot "
                "%1 is not missing in %2 here (D marks this frame only)")
            .arg(KnotName(knot()), QString::fromStdString(session_->camera_names()[camera()])),
        8000);
    return;
  }
  const int last = session_->MarkHiddenRun(camera(), frame(), knot());
  statusBar()->showMessage(
      QString("Marked knot %1 hidden in %2, frames %3-%4 (%5 frames): the tools will not label "
              "it there (Ctrl+Z undoes)")
          .arg(KnotName(knot()), QString::fromStdString(session_->camera_names()[camera()]))
          .arg(session_->frame_number(frame()))
          .arg(session_->frame_number(last))
          .arg(last - frame() + 1),
      10000);
}

// ---------------------------------------------------------------------------------------------
// The Fill Grid preview (G): what the epipolar check and Fill Grid would change, computed on a
// worker from a snapshot, drawn as ghosts with a banner; Enter applies it, Esc discards it.

void MainWindow::BuildPreviewBanner() {
  // A bar above the views, in the pink of the ghosts: what is pending and how to answer it.
  auto* banner = new QFrame;
  banner->setObjectName("preview_banner");
  banner->setStyleSheet(QString("#preview_banner { background: #4a1838; border: 2px solid %1; "
                                "border-radius: 3px; } #preview_banner QLabel { color: white; }")
                            .arg(QColor::fromRgb(CameraView::kGhostColour).name()));
  auto* row = new QHBoxLayout(banner);
  row->setContentsMargins(8, 3, 4, 3);
  preview_text_ = new QLabel;
  preview_text_->setTextFormat(Qt::RichText);
  preview_text_->setWordWrap(true);
  row->addWidget(preview_text_, 1);
  // Buttons for the mouse; they take no focus, so Enter and Esc stay the window's.
  for (QAction* action : {accept_preview_, discard_preview_}) {
    auto* button = new QPushButton(action == accept_preview_ ? "Accept" : "Discard");
    button->setFocusPolicy(Qt::NoFocus);
    connect(button, &QPushButton::clicked, action, &QAction::trigger);
    row->addWidget(button);
  }
  banner->hide();
  preview_banner_ = banner;
  qobject_cast<QVBoxLayout*>(workspace_->layout())->insertWidget(0, banner);
  accept_preview_->setEnabled(false);
  discard_preview_->setEnabled(false);
}

void MainWindow::StartPreview(bool from_corners) {
  // A new request replaces any other (a running one's answer is dropped).
  DropPreview({});
  preview_frame_ = frame();
  preview_corners_ = from_corners;
  preview_text_->setText(QString("<b>%1, frame %2:</b> %3…")
                             .arg(PreviewName(from_corners))
                             .arg(session_->frame_number(frame()))
                             .arg(from_corners ? "Find Path from the seeded corners, then the "
                                                 "epipolar check and Fill Grid"
                                               : "searching"));
  preview_banner_->show();
  discard_preview_->setEnabled(true);
  // The snapshot on the GUI thread; the worker never touches the document.
  previewer_.Request([session = static_cast<const Session*>(session_.get()),
                      snapshot = session_->document().labels(), t = preview_frame_,
                      corners = from_corners](const CancelToken&) {
    return session->PreviewFillGrid(snapshot, t, corners);
  });
}

void MainWindow::OnPreviewReady(Session::FillGridPreview preview) {
  if (!session_ || preview_frame_ < 0) return;  // dropped
  if (preview.empty()) {
    const int frame = preview_frame_;
    DropPreview({});
    statusBar()->showMessage(
        EmptyPreviewMessage(preview.from_corners, session_->frame_number(frame)), 8000);
    return;
  }
  preview_ = std::move(preview);
  accept_preview_->setEnabled(true);
  ShowPreviewBanner();
  RefreshOverlays();
}

void MainWindow::ShowPreviewBanner() {
  // The first key of an action, as the keyboard names it (Qt's "Return" is the Enter key).
  const auto keys = [](const QAction* a) {
    if (a->shortcuts().isEmpty()) return QString("(no key)");
    const QKeySequence& k = a->shortcuts().first();
    return k == QKeySequence(Qt::Key_Return) ? QString("Enter")
                                             : k.toString(QKeySequence::NativeText);
  };
  const QString text = PreviewSummary(*preview_, session_->frame_number(preview_->t),
                                      keys(accept_preview_), keys(discard_preview_));
  preview_text_->setText(text);
  preview_banner_->show();
  statusBar()->showMessage(QTextDocumentFragment::fromHtml(text).toPlainText(), 8000);
}

void MainWindow::AcceptPreview() {
  if (!session_ || !preview_ || busy()) return;
  // Dropped before it is applied: the change it makes must not discard it a second time.
  const Session::FillGridPreview preview = std::move(*preview_);
  DropPreview({});
  const int changed = session_->ApplyFillGridPreview(preview);
  statusBar()->showMessage(
      AppliedPreviewMessage(preview, session_->frame_number(preview.t), changed), 8000);
}

void MainWindow::DropPreview(const QString& why) {
  if (preview_frame_ < 0) return;
  previewer_.Drop();  // a result still on its way is dropped
  preview_frame_ = -1;
  preview_.reset();
  preview_banner_->hide();
  accept_preview_->setEnabled(false);
  discard_preview_->setEnabled(false);
  RefreshOverlays();
  if (!why.isEmpty()) statusBar()->showMessage(PreviewName(preview_corners_) + " " + why, 6000);
}

bool MainWindow::WaitForIdle(int timeout_ms) {
  const auto idle = [this] {
    return (frame_shown_ || !session_) && !previewing() && !previewer_.running() && !busy() &&
           !checker_.pending() &&
           !(room_ == Room::kSimulation &&
             (simulation_room_->busy() || !simulation_room_->frame_shown())) &&
           !(room_ == Room::kReconstruction && reconstruction_room_->busy());
  };
  WaitUntil(idle, timeout_ms);
  return idle();
}

// ---------------------------------------------------------------------------------------------
// The rooms: recording, calibration, labeling.

void MainWindow::BuildRooms() {
  for (const char* name : {"Recording", "Calibration", "Labeling", "Reconstruction", "Simulation"})
    rooms_->addTab(name);
  rooms_->setCurrentIndex(static_cast<int>(Room::kLabeling));
  rooms_->hide();  // until a project is open
  connect(rooms_, &QTabBar::currentChanged, this,
          [this](int index) { ShowRoom(static_cast<Room>(index)); });
  recording_room_ = new RecordingRoom;
  stack_->addWidget(recording_room_);
  connect(recording_room_, &RecordingRoom::goToFrame, this, [this](int frame_number) {
    if (!session_) {
      statusBar()->showMessage("Frame " + QString::number(frame_number) +
                                   ": the labeling room opens with a project (File > New project)",
                               6000);
      return;
    }
    ShowRoom(Room::kLabeling);
    SetFrame(frame_number - session_->frame_number(0));
  });
  calibration_room_ = new CalibrationRoom;
  stack_->addWidget(calibration_room_);
  // The project names the saved rig now: it is opened again so that the labeling room works with
  // the rig (unsaved labels asked about first); the calibration room keeps its work.
  connect(calibration_room_, &CalibrationRoom::rigSaved, this, [this](const QString& rig) {
    if (!session_ || !calibration_) return;
    std::unique_ptr<CalibrationPresenter> work = std::move(calibration_);
    const bool reopened = OpenProject(QString::fromStdString(session_->project().path));
    if (reopened) work->SetProjectRig(&session_->rig(), session_->project().rig);
    calibration_ = std::move(work);
    ShowRoom(Room::kCalibration);
    statusBar()->showMessage(
        reopened ? QString("Rig saved to %1: the project names it, the labeling room works with it")
                       .arg(rig)
                 : QString("Rig saved to %1 and named in the project: the labeling room uses it "
                           "once the project is opened again")
                       .arg(rig),
        15000);
  });
  reconstruction_room_ = new ReconstructionRoom;
  stack_->addWidget(reconstruction_room_);
  connect(reconstruction_room_, &ReconstructionRoom::showLabel, this, &MainWindow::ShowLabel);
  connect(reconstruction_room_, &ReconstructionRoom::frameChanged, this,
          &MainWindow::RefreshStatus);
  simulation_room_ = new SimulationRoom;
  stack_->addWidget(simulation_room_);
  connect(simulation_room_, &SimulationRoom::frameChanged, this, &MainWindow::RefreshStatus);

  for (QDockWidget* dock : findChildren<QDockWidget*>()) labeling_bars_.push_back(dock);
  for (QToolBar* bar : findChildren<QToolBar*>()) labeling_bars_.push_back(bar);
}

void MainWindow::ShowRoom(Room room) {
  if (!session_ && !(room == Room::kRecording && recording_)) return;
  const bool labeling = room == Room::kLabeling;
  // The frame the person left the reconstruction or simulation room at (their sliders do not
  // load the labeling room's frames on every step: the 3D view's frame change stays fast).
  std::optional<int> left_at;
  if (room_ == Room::kReconstruction && room != room_) left_at = reconstruction_room_->frame();
  if (room_ == Room::kSimulation && room != room_) left_at = simulation_room_->frame();
  // A message of the labeling room (a label's reason, the way back to the room it came from)
  // leaves with it.
  if (room_ == Room::kLabeling && !labeling) statusBar()->clearMessage();
  room_ = room;
  {
    const QSignalBlocker block(rooms_);
    rooms_->setCurrentIndex(static_cast<int>(room));
  }
  // The labeling room's docks and tool bar leave with it (also when the window opened on another
  // room) and come back as they were.
  if (!labeling) {
    if (labeling_bars_shown_.empty())
      for (QWidget* bar : labeling_bars_) labeling_bars_shown_.push_back(!bar->isHidden());
    for (QWidget* bar : labeling_bars_) bar->hide();
  } else if (!labeling_bars_shown_.empty()) {
    for (size_t i = 0; i < labeling_bars_.size(); ++i)
      labeling_bars_[i]->setVisible(labeling_bars_shown_[i]);
    labeling_bars_shown_.clear();
  }
  for (QAction* action : labeling_actions_) action->setEnabled(labeling);
  if (labeling) {  // the preview's answers only while one is pending
    accept_preview_->setEnabled(preview_.has_value());
    discard_preview_->setEnabled(preview_frame_ >= 0);
  }
  switch (room) {
    case Room::kRecording:
      stack_->setCurrentWidget(recording_room_);
      recording_room_->Show(recording_.get());
      if (recording_ && !recording_->report() && !checker_.pending()) StartCheck();
      break;
    case Room::kCalibration:
      stack_->setCurrentWidget(calibration_room_);
      calibration_room_->Show(calibration_.get());
      break;
    case Room::kLabeling:
      stack_->setCurrentWidget(workspace_);
      if (left_at && *left_at != frame()) SetFrame(*left_at);
      RefreshKnotGrid();  // a score made in the simulation room colours it
      FocusView();
      break;
    case Room::kReconstruction:
      stack_->setCurrentWidget(reconstruction_room_);
      reconstruction_room_->Show(reconstruction_.get());
      reconstruction_room_->SetFrame(left_at.value_or(frame()));
      break;
    case Room::kSimulation:
      stack_->setCurrentWidget(simulation_room_);
      simulation_room_->Show(simulation_.get(), reconstruction_.get());
      simulation_room_->SetFrame(left_at.value_or(frame()));
      break;
  }
  RefreshStatus();
}

void MainWindow::ShowLabel(int camera, int t, int knot) {
  if (!session_ || t < 0 || t >= session_->frames()) return;
  const recon::LabelSet& labels = session_->document().labels();
  if (camera < 0)
    for (int c = 0; c < session_->cameras() && camera < 0; ++c)
      if (labels.at(c, t, knot).present()) camera = c;
  if (camera < 0) camera = 0;
  ShowRoom(Room::kLabeling);
  SetFrame(t);
  SetCamera(camera);
  SetKnot(knot);
  Maximise(camera);
  const recon::Label& label = labels.at(camera, t, knot);
  if (label.present()) views_[camera]->ZoomTo(label.px, 120.0);
  statusBar()->showMessage(
      QString("The label of knot %1 in %2 (Ctrl+4: back to the reconstruction room)")
          .arg(KnotName(knot), QString::fromStdString(session_->camera_names()[camera])),
      10000);
}

void MainWindow::StopSessionWorkers() {
  reconstruction_room_->Show(nullptr);
  simulation_room_->Show(nullptr, nullptr);
  simulation_.reset();
  reconstruction_.reset();
  review_table_->setModel(nullptr);
  presenter_.reset();
  review_model_.reset();
  // The workers read the session being replaced or closed: their answers are dropped.
  loader_.Drop();
  colours_.Drop();
  loader_.Wait();
  colours_.Wait();
  previewer_.Wait();
  tracker_.Wait();
  DropPreview({});
}

bool MainWindow::OpenRecording(const QString& experiment, QString* error) {
  if (session_ && !MaybeSave()) return false;
  std::unique_ptr<RecordingPresenter> recording;
  try {
    recording = std::make_unique<RecordingPresenter>(experiment.toStdString());
  } catch (const std::exception& e) {
    const QString why = QString::fromLocal8Bit(e.what());
    if (error != nullptr)
      *error = why.contains(experiment) ? why : QString("%1: %2").arg(experiment, why);
    else
      QMessageBox::critical(this, "Cannot open the recording",
                            QString("%1\n\n%2").arg(experiment, why));
    return false;
  }
  // The project (if any) closes: its rooms wait for the next one.
  checker_.Drop();
  checker_.Wait();
  if (session_) {
    StopSessionWorkers();
    calibration_.reset();
    session_.reset();
    setWindowModified(false);
  }
  recording_ = std::move(recording);
  setWindowTitle(QString("netlab — %1").arg(QFileInfo(experiment).fileName()));
  rooms_->show();
  for (int i = 0; i < rooms_->count(); ++i)
    rooms_->setTabEnabled(i, i == static_cast<int>(Room::kRecording));
  ShowRoom(Room::kRecording);
  return true;
}

void MainWindow::OpenRecordingDialog() {
  const QString path = QFileDialog::getOpenFileName(this, "Open a recording", {},
                                                    "Experiment (experiment.yaml *.yaml)");
  if (!path.isEmpty()) OpenRecording(path);
}

void MainWindow::StartCheck() {
  const RecordingPresenter* recording = recording_.get();
  if (recording == nullptr) return;
  statusBar()->showMessage("Checking every frame's header (netlab ingest --check)…", 4000);
  checker_.Request([recording](const CancelToken&) {
    try {
      return RecordingPresenter::Check(recording->sequence(), false);
    } catch (const std::exception& e) {
      recon::CheckReport failed;
      failed.warnings.push_back(std::string("the check failed: ") + e.what());
      return failed;
    }
  });
}

void MainWindow::OnChecked(recon::CheckReport report) {
  if (!recording_) return;
  recording_->SetReport(std::move(report));
  if (room_ == Room::kRecording) recording_room_->Show(recording_.get());
  const size_t rows = recording_->Findings().size();
  statusBar()->showMessage(rows == 0 ? QString("Recording checked: every camera whole")
                                     : QString("Recording checked: %1 finding%2 (the table)")
                                           .arg(rows)
                                           .arg(rows == 1 ? "" : "s"),
                           6000);
}

}  // namespace netlab::gui
