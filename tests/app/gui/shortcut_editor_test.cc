// The shortcut editor (F1, "Change shortcuts…") on the window's own actions, driven by real mouse
// and key events (Qt's offscreen platform): a key pressed in a key box and OK give the action the
// key, store it in the settings and a window built afterwards has it; a key on two actions names
// both and disables OK; the resets bring the defaults back and remove the settings; Cancel and Esc
// change nothing. The settings are in the test's own folder, never the person's.

#include "app/gui/shortcut_editor.h"

#include <gtest/gtest.h>

#include <QAction>
#include <QApplication>
#include <QDialogButtonBox>
#include <QLabel>
#include <QPushButton>
#include <QSettings>
#include <QSignalSpy>
#include <QStandardPaths>
#include <QTableWidget>
#include <QTest>
#include <QTimer>
#include <QToolButton>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "app/gui/main_window.h"
#include "app/gui/settings.h"

namespace netlab::gui {
namespace {

namespace fs = std::filesystem;

const fs::path& Dir() {
  static const fs::path dir =
      fs::temp_directory_path() / ("netlab_shortcut_editor_test_" + std::to_string(getpid()));
  return dir;
}

QSettings Store() { return QSettings("netlab", "netlab-gui"); }

// The settings' stored shortcuts: action name -> value.
std::map<QString, QString> Stored() {
  QSettings s("netlab", "netlab-gui");
  s.beginGroup("shortcuts");
  std::map<QString, QString> stored;
  for (const QString& key : s.allKeys()) stored[key] = s.value(key).toString();
  return stored;
}

std::vector<QAction*> ActionsOf(MainWindow& w) {
  const QList<QAction*> actions = w.actions();
  return {actions.begin(), actions.end()};
}

QAction* Action(MainWindow& w, const QString& name) {
  for (QAction* a : w.actions())
    if (a->objectName() == name) return a;
  return nullptr;
}

QList<QKeySequence> Keys(const QString& text) { return Settings::ParseKeys(text); }

// Presses `key` in a key box as a person does: a click into the box, then the key.
void Press(KeyBox* box, Qt::Key key, Qt::KeyboardModifiers modifiers = Qt::NoModifier) {
  QTest::mouseClick(box, Qt::LeftButton);
  QTest::keyClick(box, key, modifiers);
}

// Clicks the ✕ of a key box.
void ClickClear(KeyBox* box) {
  for (QToolButton* b : box->findChildren<QToolButton*>())
    if (b->isVisible()) {
      QTest::mouseClick(b, Qt::LeftButton);
      return;
    }
  ADD_FAILURE() << "no visible clear button";
}

QPushButton* Cancel(ShortcutEditor& editor) {
  return editor.findChild<QDialogButtonBox*>()->button(QDialogButtonBox::Cancel);
}

class ShortcutEditorTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fs::remove_all(Dir());
    fs::create_directories(Dir());
  }
  static void TearDownTestSuite() {
    if (!getenv("NETLAB_KEEP_TEST_FILES")) fs::remove_all(Dir());
  }
  void SetUp() override {
    // main() chose this process's settings folder before any QSettings.
    ASSERT_TRUE(Store().fileName().startsWith(QString::fromStdString(Dir().string())))
        << Store().fileName().toStdString();
    Store().remove("shortcuts");
    window_ = std::make_unique<MainWindow>();
  }
  void TearDown() override { Store().remove("shortcuts"); }

  // An editor of the window's actions, shown.
  std::unique_ptr<ShortcutEditor> Open() {
    auto editor = std::make_unique<ShortcutEditor>(ActionsOf(*window_));
    editor->show();
    EXPECT_TRUE(QTest::qWaitForWindowExposed(editor.get()));
    return editor;
  }
  int Row(ShortcutEditor& editor, const QString& name) {
    const int row = editor.RowOf(name);
    EXPECT_GE(row, 0) << name.toStdString();
    return row;
  }

  std::unique_ptr<MainWindow> window_;
};

TEST_F(ShortcutEditorTest, TheSettingsTextHoldsEveryKeyIncludingTheSeparator) {
  EXPECT_EQ(Keys("F;Right"),
            (QList<QKeySequence>{QKeySequence(Qt::Key_F), QKeySequence(Qt::Key_Right)}));
  EXPECT_EQ(Keys(" F ; Right "), Keys("F;Right"));
  EXPECT_EQ(Keys("+;="),
            (QList<QKeySequence>{QKeySequence(Qt::Key_Plus), QKeySequence(Qt::Key_Equal)}));
  EXPECT_TRUE(Keys("").isEmpty());
  // ";" itself: alone, after a separator, after a modifier.
  const QKeySequence semicolon(Qt::Key_Semicolon), ctrl_semicolon(Qt::CTRL | Qt::Key_Semicolon);
  EXPECT_EQ(Keys(";"), QList<QKeySequence>{semicolon});
  EXPECT_EQ(Keys("A;;"), (QList<QKeySequence>{QKeySequence(Qt::Key_A), semicolon}));
  EXPECT_EQ(Keys(";;A"), (QList<QKeySequence>{semicolon, QKeySequence(Qt::Key_A)}));
  EXPECT_EQ(Keys("Ctrl+;;,"), (QList<QKeySequence>{ctrl_semicolon, QKeySequence(Qt::Key_Comma)}));
  EXPECT_EQ(Keys("Ctrl++;;"),
            (QList<QKeySequence>{QKeySequence(Qt::CTRL | Qt::Key_Plus), semicolon}));
  for (const QList<QKeySequence>& keys :
       {QList<QKeySequence>{semicolon, QKeySequence(Qt::Key_Comma)},
        QList<QKeySequence>{QKeySequence(Qt::Key_Comma), semicolon},
        QList<QKeySequence>{ctrl_semicolon},
        QList<QKeySequence>{QKeySequence(Qt::SHIFT | Qt::Key_BracketRight)},
        QList<QKeySequence>{QKeySequence(Qt::Key_Backslash),
                            QKeySequence(Qt::CTRL | Qt::Key_Comma)}})
    EXPECT_EQ(Keys(Settings::JoinKeys(keys)), keys) << Settings::JoinKeys(keys).toStdString();
  // Stored and read back; keys equal to the default remove the setting; "" is no keys at all.
  Settings::SetShortcut("Test action", {semicolon}, "F;Right");
  EXPECT_EQ(Settings::Shortcuts("Test action", "F;Right"), QList<QKeySequence>{semicolon});
  Settings::SetShortcut("Test action", {}, "F;Right");
  EXPECT_TRUE(Settings::HasShortcut("Test action"));
  EXPECT_TRUE(Settings::Shortcuts("Test action", "F;Right").isEmpty());
  Settings::SetShortcut("Test action", Keys("F;Right"), "F;Right");
  EXPECT_FALSE(Settings::HasShortcut("Test action"));
  EXPECT_EQ(Settings::Shortcuts("Test action", "F;Right"), Keys("F;Right"));
}

TEST_F(ShortcutEditorTest, EveryActionIsARowWithItsKeysAndDefaults) {
  auto editor = Open();
  EXPECT_EQ(editor->rows(), static_cast<int>(window_->actions().size()));
  EXPECT_GE(editor->rows(), 40);
  const int next = Row(*editor, "Next frame");
  EXPECT_EQ(editor->box(next, 0)->keys(), QKeySequence(Qt::Key_F));
  EXPECT_EQ(editor->box(next, 1)->keys(), QKeySequence(Qt::Key_Right));
  EXPECT_EQ(editor->box(next, 1)->text(), "Right");
  EXPECT_EQ(editor->DefaultKeys(next), Keys("F;Right"));
  const int save = Row(*editor, "Save labels");
  EXPECT_EQ(editor->box(save, 0)->text(),
            QKeySequence("Ctrl+S").toString(QKeySequence::NativeText));
  EXPECT_TRUE(editor->box(save, 1)->keys().isEmpty());
  // Every default reads as the window always read it (split at ";").
  for (QAction* a : window_->actions()) {
    const QString defaults = a->property(ShortcutEditor::kDefaultKeysProperty).toString();
    QList<QKeySequence> split;
    for (const QString& k : defaults.split(";", Qt::SkipEmptyParts)) split << QKeySequence(k);
    EXPECT_EQ(Keys(defaults), split) << defaults.toStdString();
    EXPECT_EQ(a->shortcuts(), split) << defaults.toStdString();
  }
  // The find box shows the rows whose action or keys hold its text.
  const auto shown = [&] {
    QStringList rows;
    for (int r = 0; r < editor->rows(); ++r)
      if (!editor->table()->isRowHidden(r)) rows << editor->table()->item(r, 0)->text();
    return rows;
  };
  auto* find = editor->findChild<QLineEdit*>("find");
  ASSERT_NE(find, nullptr);
  QTest::keyClicks(find, "BRUSH");
  EXPECT_EQ(shown(), (QStringList{"Larger brush", "Smaller brush"}));
  find->clear();
  QTest::keyClicks(find, "shift+b");
  EXPECT_EQ(shown(), QStringList{"Back 10 frames"});
  find->clear();
  EXPECT_EQ(shown().size(), editor->rows());
  // Nothing changed yet: no row to reset, no conflict, OK available.
  for (int r = 0; r < editor->rows(); ++r) EXPECT_FALSE(editor->reset_button(r)->isEnabled()) << r;
  EXPECT_TRUE(editor->Conflicts().isEmpty());
  EXPECT_TRUE(editor->ok_button()->isEnabled());
}

TEST_F(ShortcutEditorTest, AKeyPressedInABoxAndOkChangeTheActionTheSettingsAndTheNextWindow) {
  auto editor = Open();
  const int row = Row(*editor, "Show labels");
  Press(editor->box(row, 0), Qt::Key_W, Qt::ControlModifier);
  Press(editor->box(row, 1), Qt::Key_F9);
  EXPECT_EQ(editor->box(row, 0)->keys(), QKeySequence(Qt::CTRL | Qt::Key_W));
  EXPECT_EQ(editor->Keys(row), Keys("Ctrl+W;F9"));
  EXPECT_TRUE(editor->reset_button(row)->isEnabled());
  EXPECT_TRUE(editor->table()->item(row, 0)->font().bold());
  // Modifiers alone record nothing; Shift stays with a letter, a named key, not a symbol it types.
  const int zoom = Row(*editor, "Zoom every view on the knot");
  QTest::keyClick(editor->box(zoom, 1), Qt::Key_Shift, Qt::ShiftModifier);
  EXPECT_TRUE(editor->box(zoom, 1)->keys().isEmpty());
  QTest::keyClick(editor->box(zoom, 1), Qt::Key_Y, Qt::ShiftModifier);
  EXPECT_EQ(editor->box(zoom, 1)->keys(), QKeySequence(Qt::SHIFT | Qt::Key_Y));
  QTest::keyClick(editor->box(zoom, 1), Qt::Key_PageDown, Qt::ShiftModifier);
  EXPECT_EQ(editor->box(zoom, 1)->keys(), QKeySequence(Qt::SHIFT | Qt::Key_PageDown));
  QTest::keyClick(editor->box(zoom, 1), Qt::Key_Exclam, Qt::ShiftModifier);
  EXPECT_EQ(editor->box(zoom, 1)->keys(), QKeySequence(Qt::Key_Exclam));
  QTest::mouseClick(editor->ok_button(), Qt::LeftButton);
  EXPECT_EQ(editor->result(), QDialog::Accepted);
  EXPECT_FALSE(editor->isVisible());

  QAction* labels = Action(*window_, "Show labels");
  EXPECT_EQ(labels->shortcuts(), Keys("Ctrl+W;F9"));
  EXPECT_EQ(Action(*window_, "Zoom every view on the knot")->shortcuts(), Keys("Z;!"));
  // Only the changed actions are stored.
  const std::map<QString, QString> stored = Stored();
  EXPECT_EQ(stored.size(), 2u);
  EXPECT_EQ(Store().value("shortcuts/Show labels").toString(), "Ctrl+W;F9");
  EXPECT_EQ(Store().value("shortcuts/Zoom every view on the knot").toString(), "Z;!");

  // A window built afterwards has them, and its shortcut runs the action.
  MainWindow next;
  next.show();
  next.activateWindow();
  ASSERT_TRUE(QTest::qWaitForWindowActive(&next));
  QAction* again = Action(next, "Show labels");
  ASSERT_NE(again, nullptr);
  EXPECT_EQ(again->shortcuts(), Keys("Ctrl+W;F9"));
  QSignalSpy triggered(again, &QAction::triggered);
  QTest::keyClick(&next, Qt::Key_W, Qt::ControlModifier);
  QTest::keyClick(&next, Qt::Key_L);  // the old key does nothing now
  EXPECT_EQ(triggered.count(), 1);

  // Back to the default keys by pressing them: the setting goes.
  auto back = std::make_unique<ShortcutEditor>(ActionsOf(next));
  back->show();
  ASSERT_TRUE(QTest::qWaitForWindowExposed(back.get()));
  const int r = back->RowOf("Show labels");
  Press(back->box(r, 0), Qt::Key_L);
  ClickClear(back->box(r, 1));
  EXPECT_EQ(back->Keys(r), Keys("L"));
  EXPECT_FALSE(back->reset_button(r)->isEnabled());  // it is the default again
  QTest::mouseClick(back->ok_button(), Qt::LeftButton);
  EXPECT_EQ(again->shortcuts(), Keys("L"));
  EXPECT_FALSE(Settings::HasShortcut("Show labels"));
  EXPECT_TRUE(Settings::HasShortcut("Zoom every view on the knot"));
}

TEST_F(ShortcutEditorTest, AKeyOnTwoActionsNamesBothAndDisablesOk) {
  auto editor = Open();
  const int labels = Row(*editor, "Show labels"), previous = Row(*editor, "Previous frame");
  Press(editor->box(labels, 1), Qt::Key_B);  // "Previous frame" has B
  EXPECT_FALSE(editor->ok_button()->isEnabled());
  ASSERT_EQ(editor->Conflicts().size(), 1);
  const QString line = editor->Conflicts()[0];
  EXPECT_EQ(line, "“B” is on both “Previous frame” and “Show labels”");
  EXPECT_TRUE(editor->InConflict(labels));
  EXPECT_TRUE(editor->InConflict(previous));
  EXPECT_FALSE(editor->InConflict(Row(*editor, "Next frame")));
  // Shown: the line under the table, the two boxes with B highlighted, not the others.
  bool shown = false;
  for (QLabel* label : editor->findChildren<QLabel*>())
    shown = shown || (label->isVisible() && label->text().contains("“Previous frame” and "
                                                                   "“Show labels”"));
  EXPECT_TRUE(shown);
  EXPECT_FALSE(editor->box(labels, 1)->styleSheet().isEmpty());
  EXPECT_FALSE(editor->box(previous, 0)->styleSheet().isEmpty());
  EXPECT_TRUE(editor->box(labels, 0)->styleSheet().isEmpty());
  EXPECT_TRUE(editor->box(previous, 1)->styleSheet().isEmpty());
  QTest::qWait(300);  // the boxes' ✕ fade in
  editor->grab().save((Dir() / "shortcut_editor_conflict.png").string().c_str());

  // OK does nothing meanwhile (accept() refuses too).
  QTest::mouseClick(editor->ok_button(), Qt::LeftButton);
  editor->accept();
  EXPECT_TRUE(editor->isVisible());
  EXPECT_EQ(Action(*window_, "Show labels")->shortcuts(), Keys("L"));
  EXPECT_TRUE(Stored().empty());

  // A third holder is named too; clearing two of them with ✕ ends the conflict.
  const int accept = Row(*editor, "Accept label");
  Press(editor->box(accept, 1), Qt::Key_B);
  ASSERT_EQ(editor->Conflicts().size(), 1);
  EXPECT_EQ(editor->Conflicts()[0], "“B” is on “Previous frame”, “Accept label” and “Show labels”");
  ClickClear(editor->box(labels, 1));
  ClickClear(editor->box(accept, 1));
  EXPECT_TRUE(editor->Conflicts().isEmpty());
  EXPECT_FALSE(editor->InConflict(previous));
  EXPECT_TRUE(editor->box(previous, 0)->styleSheet().isEmpty());
  EXPECT_TRUE(editor->ok_button()->isEnabled());
  // A key in both boxes of one row is no conflict (the row has it once).
  Press(editor->box(labels, 1), Qt::Key_L);
  EXPECT_TRUE(editor->Conflicts().isEmpty());
  EXPECT_EQ(editor->Keys(labels), Keys("L"));
}

TEST_F(ShortcutEditorTest, ResetsBringTheDefaultsBackAndRemoveTheSettings) {
  Store().setValue("shortcuts/Show labels", "Ctrl+W");
  Store().setValue("shortcuts/Next frame", "N;Right");
  Store().setValue("shortcuts/Undo", "");
  window_ = std::make_unique<MainWindow>();
  EXPECT_EQ(Action(*window_, "Show labels")->shortcuts(), Keys("Ctrl+W"));
  EXPECT_TRUE(Action(*window_, "Undo")->shortcuts().isEmpty());

  auto editor = Open();
  const int labels = Row(*editor, "Show labels"), next = Row(*editor, "Next frame"),
            undo = Row(*editor, "Undo");
  EXPECT_EQ(editor->box(next, 0)->keys(), QKeySequence(Qt::Key_N));
  EXPECT_TRUE(editor->box(undo, 0)->keys().isEmpty());
  for (int r : {labels, next, undo}) {
    EXPECT_TRUE(editor->reset_button(r)->isEnabled()) << r;
    EXPECT_TRUE(editor->table()->item(r, 0)->font().bold()) << r;
  }
  // One row: only that row.
  QTest::mouseClick(editor->reset_button(next), Qt::LeftButton);
  EXPECT_EQ(editor->Keys(next), Keys("F;Right"));
  EXPECT_FALSE(editor->reset_button(next)->isEnabled());
  EXPECT_EQ(editor->Keys(labels), Keys("Ctrl+W"));
  // Then all, and OK.
  QTest::mouseClick(editor->reset_all_button(), Qt::LeftButton);
  for (int r = 0; r < editor->rows(); ++r) {
    EXPECT_EQ(editor->Keys(r), editor->DefaultKeys(r)) << r;
    EXPECT_FALSE(editor->reset_button(r)->isEnabled()) << r;
  }
  EXPECT_EQ(editor->box(undo, 0)->keys(), QKeySequence("Ctrl+Z"));
  QTest::mouseClick(editor->ok_button(), Qt::LeftButton);
  EXPECT_EQ(Action(*window_, "Show labels")->shortcuts(), Keys("L"));
  EXPECT_EQ(Action(*window_, "Next frame")->shortcuts(), Keys("F;Right"));
  EXPECT_EQ(Action(*window_, "Undo")->shortcuts(), Keys("Ctrl+Z"));
  EXPECT_TRUE(Stored().empty());
}

TEST_F(ShortcutEditorTest, AHandEditedThirdKeyStaysUntilItsRowIsEdited) {
  Store().setValue("shortcuts/Redo", "Ctrl+Shift+Z;Ctrl+Y;F12");
  window_ = std::make_unique<MainWindow>();
  auto editor = Open();
  const int redo = Row(*editor, "Redo");
  EXPECT_EQ(editor->Keys(redo), Keys("Ctrl+Shift+Z;Ctrl+Y;F12"));
  // F12 counts in conflicts.
  const int first = Row(*editor, "First frame");
  Press(editor->box(first, 1), Qt::Key_F12);
  EXPECT_EQ(editor->Conflicts(), QStringList{"“F12” is on both “Redo” and “First frame”"});
  ClickClear(editor->box(first, 1));
  QTest::mouseClick(editor->ok_button(), Qt::LeftButton);
  EXPECT_EQ(Action(*window_, "Redo")->shortcuts(), Keys("Ctrl+Shift+Z;Ctrl+Y;F12"));
  // An edit of the row leaves it the keys of its boxes.
  editor = Open();
  Press(editor->box(redo, 1), Qt::Key_Y, Qt::ControlModifier | Qt::AltModifier);
  EXPECT_EQ(editor->Keys(redo), Keys("Ctrl+Shift+Z;Ctrl+Alt+Y"));
  QTest::mouseClick(editor->ok_button(), Qt::LeftButton);
  EXPECT_EQ(Store().value("shortcuts/Redo").toString(), "Ctrl+Shift+Z;Ctrl+Alt+Y");
}

TEST_F(ShortcutEditorTest, CancelAndEscChangeNothing) {
  Store().setValue("shortcuts/Next frame", "N;Right");
  window_ = std::make_unique<MainWindow>();
  for (const bool escape : {false, true}) {
    auto editor = Open();
    const int labels = Row(*editor, "Show labels"), next = Row(*editor, "Next frame");
    Press(editor->box(labels, 0), Qt::Key_W, Qt::ControlModifier);
    QTest::mouseClick(editor->reset_all_button(), Qt::LeftButton);
    // Enter is a key like any other in a box, and does not close the dialog (nor in the find
    // box: there is no default button).
    Press(editor->box(next, 1), Qt::Key_Return);
    EXPECT_EQ(editor->box(next, 1)->keys(), QKeySequence(Qt::Key_Return));
    auto* find = editor->findChild<QLineEdit*>("find");
    ASSERT_NE(find, nullptr);
    QTest::keyClick(find, Qt::Key_Return);
    EXPECT_TRUE(editor->isVisible());
    EXPECT_FALSE(editor->ok_button()->isDefault());
    Press(editor->box(next, 1), Qt::Key_F8);
    if (escape)
      QTest::keyClick(editor->box(next, 1), Qt::Key_Escape);  // in a box: still the dialog's
    else
      QTest::mouseClick(Cancel(*editor), Qt::LeftButton);
    EXPECT_EQ(editor->result(), QDialog::Rejected) << escape;
    EXPECT_FALSE(editor->isVisible()) << escape;
    EXPECT_EQ(Action(*window_, "Show labels")->shortcuts(), Keys("L"));
    EXPECT_EQ(Action(*window_, "Next frame")->shortcuts(), Keys("N;Right"));
    EXPECT_EQ(Stored(), (std::map<QString, QString>{{"Next frame", "N;Right"}}));
  }
}

TEST_F(ShortcutEditorTest, TheCheatSheetOpensTheEditorAndShowsTheNewKeys) {
  MainWindow& w = *window_;
  w.resize(1200, 800);
  w.show();
  w.activateWindow();
  ASSERT_TRUE(QTest::qWaitForWindowActive(&w));
  QString before, after;
  bool editor_seen = false;
  // F1's sheet and the editor are modal: each step runs once the dialog is up, and closes what
  // is open whatever happens (a failure never leaves the test waiting).
  QTimer::singleShot(200, [&] {
    QWidget* sheet = QApplication::activeModalWidget();
    if (sheet == nullptr) return;
    auto* table = sheet->findChild<QTableWidget*>();
    QPushButton* change = nullptr;
    for (QPushButton* b : sheet->findChildren<QPushButton*>())
      if (b->text() == "Change shortcuts…") change = b;
    const auto keys_of = [&](const QString& action) {
      for (int r = 0; table && r < table->rowCount(); ++r)
        if (table->item(r, 0) && table->item(r, 0)->text() == action)
          return table->item(r, 1)->text();
      return QString();
    };
    before = keys_of("Fit every view");
    if (change != nullptr) {
      QTimer::singleShot(200, [&] {
        auto* editor = qobject_cast<ShortcutEditor*>(QApplication::activeModalWidget());
        if (editor == nullptr) return;
        editor_seen = true;
        editor->grab().save((Dir() / "shortcut_editor.png").string().c_str());
        const int row = editor->RowOf("Fit every view");
        if (row >= 0) {
          Press(editor->box(row, 1), Qt::Key_F7);
          QTest::mouseClick(editor->ok_button(), Qt::LeftButton);
        }
        if (editor->isVisible()) editor->reject();
      });
      QTest::mouseClick(change, Qt::LeftButton);  // returns once the editor is closed
    }
    after = keys_of("Fit every view");
    sheet->grab().save((Dir() / "cheat_sheet.png").string().c_str());
    sheet->close();
  });
  QTest::keyClick(&w, Qt::Key_F1);
  EXPECT_TRUE(editor_seen);
  const QString ctrl_f = QKeySequence("Ctrl+F").toString(QKeySequence::NativeText);
  EXPECT_EQ(before, ctrl_f);
  EXPECT_EQ(after, ctrl_f + "  or  F7");
  EXPECT_EQ(Action(w, "Fit every view")->shortcuts(), Keys("Ctrl+F;F7"));
  EXPECT_EQ(Store().value("shortcuts/Fit every view").toString(), "Ctrl+F;F7");
}

}  // namespace
}  // namespace netlab::gui

int main(int argc, char** argv) {
  if (qEnvironmentVariableIsEmpty("QT_QPA_PLATFORM")) qputenv("QT_QPA_PLATFORM", "offscreen");
  // Before any QSettings: never the person's settings file. Qt's test mode, and a settings
  // folder of this process (ctest -j runs the tests of this file side by side).
  QStandardPaths::setTestModeEnabled(true);
  QSettings::setPath(QSettings::NativeFormat, QSettings::UserScope,
                     QString::fromStdString((netlab::gui::Dir() / "settings").string()));
  QApplication app(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
