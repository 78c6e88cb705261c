#pragma once
// The shortcut editor (F1's "Change shortcuts…"): one row per action of the window, its keys
// editable, a conflict (one key on two actions) named in the dialog and OK disabled while there is
// one. OK gives the actions their new keys and stores them in the settings
// (Settings::kShortcutPrefix); keys equal to an action's default remove its setting, so that a
// later change of the default reaches the person.
//
// How keys are edited: each row has two key boxes (the first keys and the other keys, as the
// defaults have "F or Right"). A box records the key the person presses, modifiers included, so
// nobody has to know how Qt spells "Shift+]" or "PgDown"; a typed text cell would need that and
// a syntax. A box holds one key (with modifiers), not Qt's multi-key chords: QKeySequenceEdit
// (Qt 6.4) waits a second for more keys and shows "Ctrl+A, ..." meanwhile, which puzzles a
// person who wanted one key. Tab and Shift+Tab move between the boxes and Esc cancels the dialog,
// so they cannot be recorded; the ✕ in a box clears it.

#include <QDialog>
#include <QKeySequence>
#include <QLineEdit>
#include <QList>
#include <QString>
#include <QStringList>
#include <vector>

class QAction;
class QLabel;
class QPushButton;
class QTableWidget;
class QTableWidgetItem;
class QToolButton;

namespace netlab::gui {

// A line edit that records the key pressed in it (one key with its modifiers) instead of text.
class KeyBox : public QLineEdit {
  Q_OBJECT

 public:
  explicit KeyBox(QWidget* parent = nullptr);
  QKeySequence keys() const { return keys_; }
  // Shows `keys` (empty: none); emits KeysChanged when they differ from the shown ones.
  void SetKeys(const QKeySequence& keys);

 signals:
  // The person recorded or cleared a key (or SetKeys changed it).
  void KeysChanged();

 protected:
  bool event(QEvent* e) override;
  void keyPressEvent(QKeyEvent* e) override;
  void focusInEvent(QFocusEvent* e) override;
  void focusOutEvent(QFocusEvent* e) override;

 private:
  QKeySequence keys_;
};

class ShortcutEditor : public QDialog {
  Q_OBJECT

 public:
  // The property of an action holding its default keys ("F;Right"; MainWindow::AddAction sets
  // it). An action without it has its keys at the editor's opening as its default.
  static constexpr char kDefaultKeysProperty[] = "netlab_default_keys";

  // Edits the keys of `actions` (in this order). An action's settings name is its objectName(),
  // else its text (MainWindow::AddAction sets both to the name).
  explicit ShortcutEditor(std::vector<QAction*> actions, QWidget* parent = nullptr);

  int rows() const { return static_cast<int>(rows_.size()); }
  // The row of the action named `name` (-1: none).
  int RowOf(const QString& name) const;
  // The keys row `row` gives its action on OK (the boxes, empty ones and repeats left out).
  QList<QKeySequence> Keys(int row) const;
  QList<QKeySequence> DefaultKeys(int row) const { return rows_[row].defaults; }
  // The key box `which` (0: the first keys, 1: the other keys) of row `row`.
  KeyBox* box(int row, int which) const {
    return which == 0 ? rows_[row].first : rows_[row].second;
  }
  QToolButton* reset_button(int row) const { return rows_[row].reset; }
  QPushButton* reset_all_button() const { return reset_all_; }
  QPushButton* ok_button() const { return ok_; }
  QTableWidget* table() const { return table_; }
  // The conflicts as shown, one line each: "“B” is on both “Previous frame” and “Accept label”".
  QStringList Conflicts() const;
  // Whether row `row` is highlighted as part of a conflict.
  bool InConflict(int row) const { return rows_[row].conflict; }

  // Every row back to its default keys (the settings change on OK).
  void ResetAll();
  void ResetRow(int row);
  // Applies and stores the keys, unless there is a conflict (then the dialog stays open).
  void accept() override;

 protected:
  void showEvent(QShowEvent* e) override;

 private:
  struct Row {
    QAction* action = nullptr;
    QString name;                  // the settings name
    QString default_text;          // the default keys as AddAction got them ("F;Right")
    QList<QKeySequence> defaults;  // parsed
    QList<QKeySequence> extra;     // keys beyond two (a hand-edited setting), kept until edited
    KeyBox* first = nullptr;
    KeyBox* second = nullptr;
    QToolButton* reset = nullptr;
    QTableWidgetItem* item = nullptr;
    bool conflict = false;
  };
  void SetRow(int row, const QList<QKeySequence>& keys);
  void Refresh();  // conflicts, highlights, the changed rows' marks, OK
  void Filter(const QString& text);

  std::vector<Row> rows_;
  QTableWidget* table_ = nullptr;
  QLabel* conflicts_ = nullptr;
  QPushButton* reset_all_ = nullptr;
  QPushButton* ok_ = nullptr;
  QStringList conflict_lines_;
  bool setting_ = false;  // SetRow under way: the boxes' signals are not the person's edits
};

}  // namespace netlab::gui
