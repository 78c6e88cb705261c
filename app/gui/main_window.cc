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

#include "app/gui/camera_view.h"
#include "app/gui/knot_grid.h"
#include "app/gui/settings.h"
#include "app/gui/shortcut_editor.h"
#include "app/gui/timeline.h"

namespace netlab::gui {
namespace {

// Label colours: by state first (review: orange diamonds), then by where the label came from.
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

QColor LabelColour(const recon::Label& l) {
  if (l.state == recon::LabelState::kNeedsReview) return QColor(255, 140, 0);
  switch (l.source) {
    case recon::LabelSource::kManual:
      return QColor(0, 230, 255);
    case recon::LabelSource::kFindNode:
      return QColor(80, 255, 120);
    case recon::LabelSource::kFindPath:
      return QColor(170, 255, 60);
    case recon::LabelSource::kFillGrid:
      return QColor(255, 240, 80);
    case recon::LabelSource::kTracked:
      return QColor(60, 220, 60);
    case recon::LabelSource::kProjected:  // placed from the other cameras: violet
      return QColor(200, 150, 255);
    default:
      return QColor(200, 200, 255);
  }
}

}  // namespace

MainWindow::MainWindow() {
  setWindowTitle("netlab");
  resize(1400, 980);
  stack_ = new QStackedWidget(this);
  setCentralWidget(stack_);
  BuildWelcome();
  BuildWorkspace();
  BuildActions();
  BuildPreviewBanner();
  stack_->setCurrentWidget(welcome_);
  play_timer_ = new QTimer(this);
  play_timer_->setInterval(33);
  connect(play_timer_, &QTimer::timeout, this, [this] {
    if (frame_ + 1 >= (session_ ? session_->frames() : 0))
      play_timer_->stop();
    else if (frame_shown_)
      SetFrame(frame_ + 1);
  });
  connect(&loader_, &QFutureWatcher<Loaded>::finished, this, &MainWindow::OnFrameLoaded);
  connect(&colours_, &QFutureWatcher<ColoursRead>::finished, this, &MainWindow::OnColoursRead);
}

MainWindow::~MainWindow() {
  cancel_ = true;
  tracker_.waitForFinished();
  loader_.waitForFinished();
  colours_.waitForFinished();
  previewer_.waitForFinished();
  review_table_->setModel(nullptr);
}

void MainWindow::BuildWelcome() {
  welcome_ = new QWidget;
  auto* layout = new QVBoxLayout(welcome_);
  auto* title = new QLabel(
      "<h2>netlab — knot labeling workstation</h2>"
      "<p>Open a project (project.yaml) or make one from an experiment, its "
      "rig and the net's colouring.</p>");
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
  frame_box_->setToolTip("Click to type a frame number; Enter goes there and hands the keys back "
                         "to the view");
  timeline_ = new Timeline;
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
    statusBar()->showMessage(QString("Knot %1 picked: click it in a view to label it").arg(KnotName(k)),
                             4000);
  });

  // The review queue.
  auto* dock = new QDockWidget("Review queue", this);
  dock->setObjectName("review_dock");
  review_table_ = new QTableView;
  review_table_->setSelectionBehavior(QAbstractItemView::SelectRows);
  review_table_->setSelectionMode(QAbstractItemView::SingleSelection);
  review_table_->setSortingEnabled(true);
  review_table_->horizontalHeader()->setStretchLastSection(true);
  review_table_->verticalHeader()->setVisible(false);
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
  recent_menu_ = file->addMenu("Open recent");
  connect(recent_menu_, &QMenu::aboutToShow, this, [this] {
    recent_menu_->clear();
    for (const QString& path : Settings::RecentProjects())
      recent_menu_->addAction(path, this, [this, path] { OpenProject(path); });
  });
  AddAction(file, "Save labels", "Ctrl+S", &MainWindow::Save);
  file->addSeparator();
  AddAction(file, "Quit", "Ctrl+Q", &MainWindow::Quit);

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
  review_table_->setModel(nullptr);
  review_model_.reset();
  loader_.waitForFinished();  // the workers read the session being replaced
  colours_.waitForFinished();
  previewer_.waitForFinished();
  DropPreview({});
  session_ = std::move(session);
  review_model_ = std::make_unique<ReviewModel>(&session_->document(), session_->frame_numbers());
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
  const Project& p = session_->project();
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
  stack_->setCurrentWidget(workspace_);
  camera_ = 0, maximised_ = -1, previous_knot_ = -1;
  frame_ = -1;  // no frame shown yet: SetFrame(0) loads it
  SetFrame(0);
  SetKnot(0);
  return true;
}

void MainWindow::SetFrame(int t) {
  if (!session_) return;
  t = std::clamp(t, 0, session_->frames() - 1);
  if (t == frame_) return;
  DropPreview("discarded: the frame changed");
  const int direction = frame_ < 0 ? 0 : (t > frame_ ? 1 : -1);
  frame_ = t;
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
  if (!session_ || camera_ < 0 || camera_ >= session_->cameras() || camera_ >= 4) return;
  // A spin box has the focus only when the person clicked into it: it keeps it until Enter or
  // Esc (its arrows step the frame). Anything else hands the keys to the view.
  if (qobject_cast<QAbstractSpinBox*>(QApplication::focusWidget()) != nullptr &&
      QApplication::focusWidget()->isVisible())
    return;
  if (views_[camera_]->isVisible() && !views_[camera_]->hasFocus())
    views_[camera_]->setFocus(Qt::OtherFocusReason);
}

bool MainWindow::eventFilter(QObject* watched, QEvent* event) {
  auto* box = qobject_cast<QSpinBox*>(watched);
  if (box == nullptr || (event->type() != QEvent::ShortcutOverride &&
                         event->type() != QEvent::KeyPress))
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
      box->setValue(box == frame_box_ ? session_->frame_number(frame_)
                    : box == row_box_ ? knot_ / cols
                                      : knot_ % cols);
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
  const long request = ++request_;
  const int t = frame_, level = half_ ? 1 : 0;
  Session* session = session_.get();
  if (loader_.isRunning()) return;  // OnFrameLoaded asks again for the newest frame
  std::array<double, 4> fit{};  // screen pixels per full-resolution pixel, per view
  for (int c = 0; c < session->cameras() && c < 4; ++c)
    fit[c] = views_[c]->FitScreenPerImage(session->rig_camera(c).intrinsics.width);
  const cv::Mat tone = ToneTable(gain_, 0, gamma_);
  loader_.setFuture(QtConcurrent::run([session, request, t, level, fit, tone]() {
    Loaded loaded;
    loaded.request = request;
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
  }));
}

void MainWindow::OnFrameLoaded() {
  Loaded loaded = loader_.result();
  if (!session_) return;
  if (loaded.request != request_ || loaded.t != frame_) {  // the person moved on
    --request_;
    RequestFrame();
    return;
  }
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
  if (!session_ || frame_ < 0 || !frame_shown_) return;
  const LabelDocument& doc = session_->document();
  const Project& p = session_->project();
  const recon::PointEstimate point = session_->Triangulate(frame_, knot_);
  for (int c = 0; c < session_->cameras() && c < 4; ++c) {
    ViewOverlay o;
    o.selected_knot = knot_;
    int to_fix = 0;  // labels under review and missing knots: which camera to work first
    for (int k = 0; k < p.knots(); ++k) {
      const recon::Label& l = doc.at(c, frame_, k);
      // (a missing knot has no label: its row's list is searched only for those)
      to_fix += l.present() ? l.state == recon::LabelState::kNeedsReview
                            : session_->missing().Find(c, frame_, k) != nullptr;
      if (!l.present()) continue;
      o.labels.push_back({k, l.px, LabelColour(l), l.state == recon::LabelState::kNeedsReview});
      // Links to the right and down neighbours that are labeled.
      for (const int n :
           {k % p.cols + 1 < p.cols ? k + 1 : -1, k + p.cols < p.knots() ? k + p.cols : -1})
        if (n >= 0 && doc.at(c, frame_, n).present())
          o.links.emplace_back(l.px, doc.at(c, frame_, n).px);
    }
    // The selected knot: its epipolar curves from the other cameras' labels, its reprojection.
    for (int other = 0; other < session_->cameras(); ++other) {
      const recon::Label& l = doc.at(other, frame_, knot_);
      if (other == c || !l.present()) continue;
      for (auto& piece : session_->EpipolarCurve(other, l.px, c)) o.epipolar.push_back(piece);
    }
    QString residual;
    if (point.valid) {
      o.reprojected = session_->rig_camera(c).ProjectWorld(point.position);
      if (doc.at(c, frame_, knot_).present())
        residual = QString(" · residual %1 px")
                       .arg((doc.at(c, frame_, knot_).px - *o.reprojected).norm(), 0, 'f', 2);
    }
    o.candidates = candidates_[c];
    o.ghosts = PreviewGhosts(c);
    o.caption = QString("%1 · frame %2 · %3 · knot %4%5")
                    .arg(QString::fromStdString(session_->camera_names()[c]))
                    .arg(session_->frame_number(frame_))
                    .arg(to_fix > 0 ? QString("%1 to fix").arg(to_fix) : QString("nothing to fix"))
                    .arg(KnotName(knot_), residual);
    MarkExpected(c, &o);
    views_[c]->SetOverlay(std::move(o));
  }
  RefreshKnotGrid();
}

void MainWindow::RefreshKnotGrid() {
  if (!session_ || frame_ < 0) return;
  const LabelDocument& doc = session_->document();
  std::vector<KnotGrid::Cell> cells(session_->project().knots());
  for (int k = 0; k < static_cast<int>(cells.size()); ++k) {
    const recon::Label& l = doc.at(camera_, frame_, k);
    if (l.state == recon::LabelState::kHidden)
      cells[k].hidden = true;
    else if (l.present())
      cells[k].label = LabelColour(l);
  }
  knot_grid_->SetCells(std::move(cells));
  knot_grid_->SetSelected(knot_);
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
      session_->IdentifyJunction(c, frame_, cursor_px_, views_[c]->brush_radius());
  const bool identified = hint.reading.status == recon::IdentifyStatus::kIdentified;
  knot_grid_->SetOffered(hint.reading.knots, identified);
  hint_camera_ = c;
  const QString why = QString::fromStdString(hint.reading.why);
  QString message;
  if (!hint.found) {
    message = "Identify: " + why;
  } else if (identified) {
    SetKnot(hint.reading.knots.front());
    message = QString("Identify: the colours say knot %1 (picked; click the junction to label it) — %2")
                  .arg(KnotName(knot_), why);
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
  if (!session_ || frame_ < 0) return;
  status_frame_->setText(QString("frame %1 (%2 of %3) · t = %4 s · %5")
                             .arg(session_->frame_number(frame_))
                             .arg(frame_ + 1)
                             .arg(session_->frames())
                             .arg(session_->frame_number(frame_) / session_->fps(), 0, 'f', 4)
                             .arg(QString::fromStdString(session_->camera_names()[camera_])));
  const recon::PointEstimate point = session_->Triangulate(frame_, knot_);
  status_knot_->setText(
      QString("knot %1%2")
          .arg(KnotName(knot_), point.valid
                                    ? QString(" · RMS residual %1 px").arg(point.rms_px, 0, 'f', 2)
                                    : QString()));
  colours_timer_->start();
}

void MainWindow::RequestColours() {
  if (!session_ || frame_ < 0 || !colours_label_->isVisible()) return;
  const recon::Label& label = session_->document().at(camera_, frame_, knot_);
  const QString where = QString("knot %1 in %2, frame %3")
                            .arg(KnotName(knot_))
                            .arg(QString::fromStdString(session_->camera_names()[camera_]))
                            .arg(session_->frame_number(frame_));
  ++colours_request_;
  if (!label.present()) {
    colours_label_->setText(QString("<b>%1</b>: no label.").arg(where));
    return;
  }
  if (colours_.isRunning()) {  // OnColoursRead asks again for the newest selection
    colours_again_ = true;
    return;
  }
  colours_label_->setText(QString("<b>%1</b>: reading the yarns…").arg(where));
  const Session* session = session_.get();
  const long request = colours_request_;
  const int c = camera_, t = frame_, k = knot_;
  const Eigen::Vector2d px = label.px;
  const recon::YarnDirections yarns =
      recon::AcceptedNeighbourYarns(session_->document().labels(), c, t, k);
  colours_.setFuture(QtConcurrent::run([session, request, c, t, k, px, yarns] {
    return ColoursRead{request, session->CheckKnotColours(c, t, k, px, yarns)};
  }));
}

void MainWindow::OnColoursRead() {
  const ColoursRead read = colours_.result();
  if (!session_) return;
  if (colours_again_ || read.request != colours_request_) {  // the selection moved on
    colours_again_ = false;
    RequestColours();
    return;
  }
  if (!read.colours) {
    colours_label_->setText("No colouring in the project, or the frame cannot be read.");
    return;
  }
  const Session::KnotColours& k = *read.colours;
  QString text = QString("<b>knot %1 in %2, frame %3</b><br>expected, by link:<br>")
                     .arg(KnotName(knot_))
                     .arg(QString::fromStdString(session_->camera_names()[camera_]))
                     .arg(session_->frame_number(frame_));
  for (const auto& link : k.expected)
    text += QString("<span style=\"background-color:rgb(%1,%2,%3)\">&nbsp;&nbsp;&nbsp;&nbsp;"
                    "</span> %4 towards %5<br>")
                .arg(std::lround(link.srgb[0]))
                .arg(std::lround(link.srgb[1]))
                .arg(std::lround(link.srgb[2]))
                .arg(QString::fromStdString(link.dye), QString::fromStdString(link.side));
  const char* colour = k.verdict == "consistent" ? "#1b7837"
                       : k.verdict == "mismatch" ? "#b2182b"
                                                 : "#555555";
  const char* meaning = k.verdict == "consistent" ? "the label's knot"
                        : k.verdict == "mismatch"   ? "not the label's knot: check it"
                                                    : "too few yarns read for sure: no evidence "
                                                      "either way";
  text += QString("<br>the yarns say: <b style=\"color:%1\">%2</b> (%3)")
              .arg(colour, QString::fromStdString(k.verdict), meaning);
  if (!k.knots_read.empty() && k.knots_read.size() <= 3) {
    QStringList names;
    for (int n : k.knots_read) names << KnotName(n);
    text += QString(" · they fit %1").arg(names.join(", "));
  }
  if (!k.why.empty()) text += "<br><small>" + QString::fromStdString(k.why).toHtmlEscaped() + "</small>";
  colours_label_->setText(text);
}

void MainWindow::OnLabelsChanged(const QList<int>& frames) {
  DropPreview("discarded: the labels changed");
  timeline_->SetReviewFrames(session_->document().ReviewFrames());
  if (frames.contains(frame_)) {
    RefreshOverlays();
    RefreshStatus();
  }
}

QString MainWindow::KnotName(int knot) const {
  if (!session_) return {};
  return QString("(%1, %2)")
      .arg(knot / session_->project().cols)
      .arg(knot % session_->project().cols);
}

void MainWindow::SetCamera(int c) {
  if (!session_ || c < 0 || c >= session_->cameras()) return;
  if (c != hint_camera_) ClearHint();
  camera_ = c;
  // One camera shown alone: the camera acted on is the one shown.
  if (maximised_ >= 0 && maximised_ != c) Maximise(c);
  RefreshKnotGrid();
  RefreshStatus();
  FocusView();
}

void MainWindow::SetKnot(int knot) {
  if (!session_) return;
  knot = std::clamp(knot, 0, session_->project().knots() - 1);
  if (knot != knot_) previous_knot_ = knot_;
  knot_ = knot;
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
  const LabelKey key{camera, frame_, knot_};
  const bool was_review = InQueue(camera, frame_, knot_);  // a review item or a missing knot
  if (modifiers & Qt::ShiftModifier) {  // exactly where clicked: the person's own label
    session_->PlaceLabel(camera, frame_, knot_, px, "Place " + KnotName(knot_).toStdString());
    statusBar()->showMessage(QString("Placed knot %1 by hand").arg(KnotName(knot_)), 4000);
    AdvanceAfterFix(key, was_review);
    return;
  }
  const recon::FindNodeResult r =
      session_->FindNode(camera, frame_, knot_, px, views_[camera]->brush_radius());
  candidates_[camera].clear();
  switch (r.status) {
    case recon::FindNodeStatus::kFound: {
      const bool review =
          session_->document().at(camera, frame_, knot_).state == recon::LabelState::kNeedsReview;
      // The reason without its own "Find Node: ", which the message already leads with.
      QString reason = QString::fromStdString(session_->document().Reason(camera, frame_, knot_));
      if (reason.startsWith("Find Node: ")) reason.remove(0, 11);
      const QString how = r.projected ? "accepted: " + QString::fromStdString(r.why)
                          : review    ? "found, kept for review: " + reason
                                      : "found and accepted";
      statusBar()->showMessage(QString("Find Node: knot %1 %2").arg(KnotName(knot_), how), 6000);
      if (!review) AdvanceAfterFix(key, was_review);
      break;
    }
    case recon::FindNodeStatus::kNone:
      statusBar()->showMessage("Find Node: no knot in the brush (" + QString::fromStdString(r.why) +
                                   "); Shift+click places the label exactly",
                               8000);
      break;
    case recon::FindNodeStatus::kSeveral:
      for (const recon::Junction& j : r.candidates) candidates_[camera].push_back(j.px);
      statusBar()->showMessage(QString("Find Node: %1 junctions in the brush (red crosses); "
                                       "click closer with a smaller brush (-), or Shift+click")
                                   .arg(r.candidates.size()),
                               8000);
      RefreshOverlays();
      break;
  }
}

void MainWindow::OnDrag(int camera, int knot, const Eigen::Vector2d& px) {
  if (!session_ || busy()) return;
  session_->PlaceLabel(camera, frame_, knot, px, "Move " + KnotName(knot).toStdString());
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
      this, "New project: the net's colouring, coloring.yaml (Cancel: none)",
      QFileInfo(rig).path(), "Colouring (*.yaml)");
  int rows = 0, cols = 0;
  if (coloring.isEmpty()) {  // the grid from the person: rows and columns (Net B is 17 x 17)
    bool ok = false;
    rows = QInputDialog::getInt(this, "New project: the net", "Knots in a column (rows):", 11, 2,
                                1000, 1, &ok);
    if (!ok) return;
    cols = QInputDialog::getInt(this, "New project: the net", "Knots in a row (columns):", rows,
                                2, 1000, 1, &ok);
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
  const QString path = QFileDialog::getSaveFileName(
      this, "New project: save the project as", QFileInfo(labels).path() + "/project.yaml",
      "Project (*.yaml)");
  if (path.isEmpty()) return;
  try {
    Project project = MakeProject(experiment.toStdString(), rig.toStdString(),
                                  coloring.toStdString(), labels.toStdString(), rows, cols);
    project.knotless = balls == QMessageBox::No;
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
      this, "Go to frame", "Frame number:", session_->frame_number(frame_),
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
  if (!session_ || !review_model_ || review_model_->rowCount() == 0) {
    statusBar()->showMessage("Nothing to review", 3000);
    return;
  }
  const LabelKey here{camera_, frame_, knot_};
  ShowReviewRow(backwards ? review_model_->Previous(here) : review_model_->Next(here));
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
  reviewing_ = LabelKey{c, t, k};
  reviewing_missing_ = review_model_->IsMissing(row);
  SetFrame(t);
  SetCamera(c);
  SetKnot(k);
  if (maximised_ != c) Maximise(c);
  ZoomOnKnot();
  const QModelIndex index = review_proxy_->mapFromSource(review_model_->index(row, 0));
  review_table_->selectRow(index.row());
  if (review_model_->IsMissing(row)) {
    ShowMissingItem(row);
    return;
  }
  statusBar()->showMessage(
      QString("Review %1 of %2: %3 — A accepts, a click fixes with Find Node, D deletes")
          .arg(row + 1)
          .arg(review_model_->rowCount())
          .arg(review_model_->index(row, ReviewModel::kReason).data().toString()),
      10000);
}

void MainWindow::AcceptSelected() {
  if (!session_ || busy()) return;
  const bool was_review = InQueue(camera_, frame_, knot_);
  session_->AcceptLabel(camera_, frame_, knot_);
  AdvanceAfterFix({camera_, frame_, knot_}, was_review);
}

void MainWindow::DeleteSelected() {
  if (!session_ || busy()) return;
  const bool was_queued = InQueue(camera_, frame_, knot_);
  if (!session_->document().at(camera_, frame_, knot_).present())
    HideSelected();  // no label here: the person says the knot is not visible
  else
    session_->DeleteLabel(camera_, frame_, knot_);
  AdvanceAfterFix({camera_, frame_, knot_}, was_queued);
}

bool MainWindow::UnderReview(int camera, int t, int knot) const {
  const recon::Label& l = session_->document().at(camera, t, knot);
  return l.present() && l.state == recon::LabelState::kNeedsReview;
}

bool MainWindow::InQueue(int camera, int t, int knot) const {
  return UnderReview(camera, t, knot) || session_->missing().Find(camera, t, knot);
}

void MainWindow::AdvanceAfterFix(const LabelKey& key, bool was_queued) {
  const auto [c, t, k] = key;
  // Only an item the window took the person to (Space, Ctrl+Home, a run's stop): a knot the
  // person labels on their own (a corner they seed) does not move the window.
  if (!was_queued || reviewing_ != key || !advance_->isChecked() || InQueue(c, t, k) ||
      review_model_->rowCount() == 0)
    return;
  // The frame's next label for review first; its missing knots (mostly the target's shadow,
  // marked hidden a run at a time with Shift+D once tracking is done) only after a missing knot.
  const std::vector<LabelKey>& items = review_model_->items();
  const int start = review_model_->Next(key), n = static_cast<int>(items.size());
  int label_row = -1, missing_row = -1;
  for (int i = 0; i < n && label_row < 0; ++i) {
    const int row = (start + i) % n;
    if (std::get<1>(items[row]) != t) continue;
    if (!review_model_->IsMissing(row))
      label_row = row;
    else if (missing_row < 0)
      missing_row = row;
  }
  if (label_row >= 0)
    ShowReviewRow(label_row);
  else if (reviewing_missing_ && missing_row >= 0)
    ShowReviewRow(missing_row);
}

void MainWindow::Nudge(double dx, double dy) {
  if (!session_ || busy()) return;
  const recon::Label& l = session_->document().at(camera_, frame_, knot_);
  if (!l.present()) return;
  // Half a pixel when a pixel is a screen pixel or larger; scaled up when zoomed out, so a nudge
  // is always visible.
  const double factor = std::max(1.0, 1.0 / std::max(views_[camera_]->scale(), 1e-3));
  session_->PlaceLabel(camera_, frame_, knot_, l.px + Eigen::Vector2d(dx, dy) * factor,
                       "Nudge " + KnotName(knot_).toStdString());
}

void MainWindow::FindPathCorners() {
  // On a worker, shown as a preview like G's: Enter applies it (two undo steps), Esc discards.
  if (session_ && !busy()) StartPreview(true);
}

void MainWindow::FindPathToPrevious() {
  if (!session_ || busy() || previous_knot_ < 0) return;
  const std::string why = session_->FindPathBetween(camera_, frame_, previous_knot_, knot_);
  statusBar()->showMessage(
      why.empty()
          ? QString("Find Path %1 → %2: done").arg(KnotName(previous_knot_), KnotName(knot_))
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
      session_->frame_number(std::min(frame_ + 30, session_->frames() - 1)),
      session_->frame_number(0), session_->frame_number(session_->frames() - 1), 1, &ok);
  if (ok) TrackTo(f - session_->frame_number(0), false, -1);  // the range asked for, in one run
}

void MainWindow::TrackTo(int to, bool wait, int max_review) {
  if (!session_ || busy() || to == frame_) return;
  DropPreview("discarded: a tracking run started");
  // A snapshot on the GUI thread; the run never touches the document.
  const int from = frame_;
  cancel_ = false;
  auto* progress = new QProgressDialog(QString("Tracking from frame %1 to %2 …")
                                           .arg(session_->frame_number(from))
                                           .arg(session_->frame_number(to)),
                                       "Cancel", 0, std::abs(to - from), this);
  progress->setWindowModality(Qt::WindowModal);
  progress->setMinimumDuration(300);
  progress->setAttribute(Qt::WA_DeleteOnClose);
  connect(progress, &QProgressDialog::canceled, this, [this] { cancel_ = true; });
  Session* session = session_.get();
  QPointer<QProgressDialog> bar(progress);
  auto report = [this, bar](int done, int) {
    QMetaObject::invokeMethod(
        this,
        [bar, done] {
          if (bar) bar->setValue(done);
        },
        Qt::QueuedConnection);
  };
  disconnect(&tracker_, nullptr, this, nullptr);
  connect(&tracker_, &QFutureWatcher<Session::TrackRun>::finished, this, [this, bar] {
    tracking_ = false;
    if (bar) bar->close();
    // The closed progress dialog may leave no window active (Qt's offscreen platform does):
    // the keys would go nowhere.
    activateWindow();
    if (QApplication::activeWindow() != this) QApplication::setActiveWindow(this);
    if (!session_) return;
    const Session::TrackRun run = tracker_.result();
    const int changed = session_->ApplyTrackRun(run);
    statusBar()->showMessage(
        QString("Tracked to frame %1: %2 labels%3")
            .arg(session_->frame_number(run.last_done))
            .arg(changed)
            .arg(run.cancelled            ? " (cancelled)"
                 : run.stopped_for_review ? QString(" (stopped: labels for review in this frame)")
                                          : QString()),
        10000);
    SetFrame(run.last_done);
    // Stopped where the person is needed: that frame's first label for review (what stopped
    // the run; the frame's missing knots wait, as after a fix), else its first item.
    if (run.stopped_for_review) {
      int first = -1, label = -1;
      for (int row = 0; row < review_model_->rowCount() && label < 0; ++row) {
        if (std::get<1>(review_model_->items()[row]) != run.last_done) continue;
        if (first < 0) first = row;
        if (!review_model_->IsMissing(row)) label = row;
      }
      if (label >= 0 || first >= 0) ShowReviewRow(label >= 0 ? label : first);
    }
  });
  tracking_ = true;
  tracker_.setFuture(QtConcurrent::run(
      [session, snapshot = session_->document().labels(), from, to, report, max_review, this]() {
        return session->Track(snapshot, from, to, &cancel_, report, max_review);
      }));
  if (wait) {
    while (busy()) QCoreApplication::processEvents(QEventLoop::AllEvents, 20);
    QCoreApplication::processEvents();
  }
}

void MainWindow::ZoomOnKnot() {
  if (!session_) return;
  // Every view onto the knot: its label, else its reprojected point.
  const recon::PointEstimate point = session_->Triangulate(frame_, knot_);
  for (int c = 0; c < session_->cameras(); ++c) {
    const recon::Label& l = session_->document().at(c, frame_, knot_);
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
    session_->cache().SetPlayhead(session_->frame_number(frame_), 0, half_ ? 1 : 0);
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

void MainWindow::ToggleMaximise() { Maximise(maximised_ >= 0 ? -1 : camera_); }

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

void MainWindow::OnMissingChanged() {
  timeline_->SetMissingFrames(session_->missing().Frames());
}

void MainWindow::ShowMissingItem(int row) {
  const auto [c, t, k] = review_model_->items()[row];
  statusBar()->showMessage(
      QString("Missing %1 of %2: %3 — click: label it · D: hidden here · Shift+D: and onwards")
          .arg(row + 1)
          .arg(review_model_->rowCount())
          .arg(QString::fromStdString(session_->missing().Reason(c, t, k))),
      15000);
}

void MainWindow::MarkExpected(int c, ViewOverlay* overlay) const {
  const recon::Label& l = session_->document().at(c, frame_, knot_);
  if (l.hidden()) {
    overlay->caption += " · marked hidden here";
  } else if (const MissingKnot* m = session_->missing().Find(c, frame_, knot_)) {
    overlay->expected = m->expected_px;
    overlay->caption += " · no label: expected in the magenta ring";
  }
}

void MainWindow::HideSelected() {
  if (!session_ || busy()) return;
  const QString where = QString("knot %1 in %2, frame %3")
                            .arg(KnotName(knot_))
                            .arg(QString::fromStdString(session_->camera_names()[camera_]))
                            .arg(session_->frame_number(frame_));
  if (session_->document().at(camera_, frame_, knot_).hidden()) {
    statusBar()->showMessage(where + " is already marked hidden; a click labels it", 6000);
    return;
  }
  session_->MarkHidden(camera_, frame_, knot_);
  statusBar()->showMessage(
      "Marked " + where + " hidden: the tools will not label it there (Ctrl+Z undoes)", 8000);
}

void MainWindow::HideSelectedOnwards() {
  if (!session_ || busy()) return;
  if (!session_->missing().Find(camera_, frame_, knot_)) {
    statusBar()->showMessage(
        QString("Shift+D marks a missing knot hidden through the frames it is missing in; knot "
                "%1 is not missing in %2 here (D marks this frame only)")
            .arg(KnotName(knot_), QString::fromStdString(session_->camera_names()[camera_])),
        8000);
    return;
  }
  const int last = session_->MarkHiddenRun(camera_, frame_, knot_);
  statusBar()->showMessage(
      QString("Marked knot %1 hidden in %2, frames %3-%4 (%5 frames): the tools will not label "
              "it there (Ctrl+Z undoes)")
          .arg(KnotName(knot_), QString::fromStdString(session_->camera_names()[camera_]))
          .arg(session_->frame_number(frame_))
          .arg(session_->frame_number(last))
          .arg(last - frame_ + 1),
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
  connect(&previewer_, &QFutureWatcher<PreviewRun>::finished, this, &MainWindow::OnPreviewReady);
}

QString MainWindow::PreviewName() const {
  return preview_corners_ ? "Find Path and Fill Grid preview" : "Fill Grid preview";
}

void MainWindow::StartPreview(bool from_corners) {
  // A new request replaces any other; one still running is asked again when it ends.
  DropPreview({});
  ++preview_request_;
  preview_frame_ = frame_;
  preview_corners_ = from_corners;
  preview_text_->setText(QString("<b>%1, frame %2:</b> %3…")
                             .arg(PreviewName())
                             .arg(session_->frame_number(frame_))
                             .arg(from_corners ? "Find Path from the seeded corners, then the "
                                                 "epipolar check and Fill Grid"
                                               : "searching"));
  preview_banner_->show();
  discard_preview_->setEnabled(true);
  if (previewer_.isRunning())
    preview_again_ = true;
  else
    LaunchPreview();
}

void MainWindow::LaunchPreview() {
  // The snapshot on the GUI thread; the worker never touches the document.
  const Session* session = session_.get();
  previewer_.setFuture(QtConcurrent::run(
      [session, snapshot = session_->document().labels(), t = preview_frame_,
       request = preview_request_, corners = preview_corners_] {
        return PreviewRun{request, session->PreviewFillGrid(snapshot, t, corners)};
      }));
}

void MainWindow::OnPreviewReady() {
  if (preview_again_ && preview_frame_ >= 0) {  // an older one ended: compute the wanted one
    preview_again_ = false;
    LaunchPreview();
    return;
  }
  const PreviewRun run = previewer_.result();
  if (!session_ || run.request != preview_request_ || preview_frame_ < 0) return;  // dropped
  if (run.preview.empty()) {
    const int frame = preview_frame_;
    DropPreview({});
    statusBar()->showMessage(
        run.preview.from_corners
            ? QString("Find Path from the corners, frame %1: nothing found; seed three or four "
                      "corners in a camera first (pick the knot, click it)")
                  .arg(session_->frame_number(frame))
            : QString("Fill Grid, frame %1: nothing to add or change; no preview pending")
                  .arg(session_->frame_number(frame)),
        8000);
    return;
  }
  preview_ = run.preview;
  accept_preview_->setEnabled(true);
  ShowPreviewBanner();
  RefreshOverlays();
}

void MainWindow::ShowPreviewBanner() {
  const Session::FillGridPreview& p = *preview_;
  // The first key of an action, as the keyboard names it (Qt's "Return" is the Enter key).
  const auto keys = [](const QAction* a) {
    if (a->shortcuts().isEmpty()) return QString("(no key)");
    const QKeySequence& k = a->shortcuts().first();
    return k == QKeySequence(Qt::Key_Return) ? QString("Enter")
                                             : k.toString(QKeySequence::NativeText);
  };
  QStringList parts;
  parts << QString("%1 new label%2 (%3 for review)")
               .arg(p.added)
               .arg(p.added == 1 ? "" : "s")
               .arg(p.added_review);
  if (p.confirmed > 0)
    parts << QString("%1 label%2 under review accepted")
                 .arg(p.confirmed)
                 .arg(p.confirmed == 1 ? "" : "s");
  if (p.to_review > 0)
    parts << QString("%1 label%2 to review").arg(p.to_review).arg(p.to_review == 1 ? "" : "s");
  if (p.moved > 0)
    parts << QString("%1 label%2 moved").arg(p.moved).arg(p.moved == 1 ? "" : "s");
  if (p.changed > 0)
    parts << QString("%1 other change%2").arg(p.changed).arg(p.changed == 1 ? "" : "s");
  const QString text =
      QString("<b>%1, frame %2:</b> %3 — dashed pink marks, not labels yet. "
              "<b>%4</b> accepts (%5), <b>%6</b> discards")
          .arg(PreviewName())
          .arg(session_->frame_number(p.t))
          .arg(parts.join(", "), keys(accept_preview_),
               p.from_corners ? "two undo steps: Find Path, Fill Grid" : "one undo step",
               keys(discard_preview_));
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
      QString("%1, frame %2: %3 labels set (%4 new, %5 of them for review; %6 under "
              "review accepted; %7 to review)")
          .arg(preview.from_corners ? "Find Path from the corners and Fill Grid" : "Fill Grid")
          .arg(session_->frame_number(preview.t))
          .arg(changed)
          .arg(preview.added)
          .arg(preview.added_review)
          .arg(preview.confirmed)
          .arg(preview.to_review),
      8000);
}

void MainWindow::DropPreview(const QString& why) {
  if (preview_frame_ < 0) return;
  ++preview_request_;  // a result still on its way is dropped
  preview_frame_ = -1;
  preview_again_ = false;
  preview_.reset();
  preview_banner_->hide();
  accept_preview_->setEnabled(false);
  discard_preview_->setEnabled(false);
  RefreshOverlays();
  if (!why.isEmpty()) statusBar()->showMessage(PreviewName() + " " + why, 6000);
}

std::vector<ViewOverlay::Ghost> MainWindow::PreviewGhosts(int c) const {
  std::vector<ViewOverlay::Ghost> ghosts;
  if (!preview_ || preview_->t != frame_) return ghosts;
  for (const recon::LabelEdit& e : preview_->edits) {
    if (e.camera != c || e.t != frame_) continue;
    const recon::Label& now = session_->document().at(c, e.t, e.knot);
    ViewOverlay::Ghost g;
    g.knot = e.knot;
    g.px = e.label.present() ? e.label.px : now.px;
    g.review = e.label.state == recon::LabelState::kNeedsReview;
    if (!e.label.present())
      g.kind = ViewOverlay::Ghost::kRemoved;
    else if (!now.present())
      g.kind = ViewOverlay::Ghost::kNew;
    else if (now.accepted() && g.review && now.px == e.label.px)
      g.kind = ViewOverlay::Ghost::kToReview;
    else
      g.kind = ViewOverlay::Ghost::kChanged, g.from = now.px;
    ghosts.push_back(g);
  }
  return ghosts;
}

bool MainWindow::WaitForIdle(int timeout_ms) {
  const auto idle = [this] {
    return frame_shown_ && !previewing() && !previewer_.isRunning() && !busy();
  };
  WaitUntil(idle, timeout_ms);
  return idle();
}

}  // namespace netlab::gui
