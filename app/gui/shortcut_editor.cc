#include "app/gui/shortcut_editor.h"

#include <QAction>
#include <QDialogButtonBox>
#include <QFocusEvent>
#include <QHBoxLayout>
#include <QHash>
#include <QHeaderView>
#include <QKeyEvent>
#include <QLabel>
#include <QPushButton>
#include <QSet>
#include <QTableWidget>
#include <QToolButton>
#include <QVBoxLayout>

#include "app/gui/settings.h"

namespace netlab::gui {
namespace {

// Keys that keep their usual meaning in a key box: Tab / Shift+Tab move on, Esc cancels.
bool PassesThrough(const QKeyEvent* e) {
  const Qt::KeyboardModifiers mods = e->modifiers() & ~Qt::KeypadModifier;
  return (e->key() == Qt::Key_Escape && mods == Qt::NoModifier) ||
         ((e->key() == Qt::Key_Tab || e->key() == Qt::Key_Backtab) &&
          !(mods & (Qt::ControlModifier | Qt::AltModifier)));
}

bool IsModifierOnly(int key) {
  switch (key) {
    case Qt::Key_Shift:
    case Qt::Key_Control:
    case Qt::Key_Meta:
    case Qt::Key_Alt:
    case Qt::Key_AltGr:
    case Qt::Key_Super_L:
    case Qt::Key_Super_R:
    case Qt::Key_Hyper_L:
    case Qt::Key_Hyper_R:
    case Qt::Key_CapsLock:
    case Qt::Key_NumLock:
    case Qt::Key_ScrollLock:
    case Qt::Key_unknown:
    case 0: return true;
    default: return false;
  }
}

QString Text(const QKeySequence& k) { return k.toString(QKeySequence::NativeText); }

QString Text(const QList<QKeySequence>& keys) {
  QStringList parts;
  for (const QKeySequence& k : keys) parts << Text(k);
  return parts.isEmpty() ? QString("no keys") : parts.join(" or ");
}

QString Quoted(const QString& s) { return QString("“%1”").arg(s); }

constexpr char kConflictStyle[] = "background: #ffc4c4;";

}  // namespace

KeyBox::KeyBox(QWidget* parent) : QLineEdit(parent) {
  setClearButtonEnabled(true);
  setPlaceholderText("none");
  setContextMenuPolicy(Qt::NoContextMenu);
  setAcceptDrops(false);
  setDragEnabled(false);
  setAttribute(Qt::WA_InputMethodEnabled, false);
  setToolTip("Click, then press the key; ✕ clears it");
  setMinimumWidth(120);
  // The text only shows the keys: the ✕ empties it (no keys); anything else (a middle-click
  // paste) is put back.
  connect(this, &QLineEdit::textChanged, this, [this](const QString& text) {
    if (text.isEmpty()) {
      if (!keys_.isEmpty()) {
        keys_ = QKeySequence();
        emit KeysChanged();
      }
    } else if (text != Text(keys_)) {
      setText(Text(keys_));
    }
  });
}

void KeyBox::SetKeys(const QKeySequence& keys) {
  if (keys == keys_) return;
  keys_ = keys;
  setText(Text(keys_));
  emit KeysChanged();
}

bool KeyBox::event(QEvent* e) {
  // Every key is the box's (the window's shortcuts do not run while a box records).
  if (e->type() == QEvent::ShortcutOverride && !PassesThrough(static_cast<QKeyEvent*>(e))) {
    e->accept();
    return true;
  }
  return QLineEdit::event(e);
}

void KeyBox::keyPressEvent(QKeyEvent* e) {
  if (PassesThrough(e)) {
    e->ignore();
    return;
  }
  e->accept();
  const int key = e->key();
  if (IsModifierOnly(key)) return;  // waits for the key that goes with them
  Qt::KeyboardModifiers mods = e->modifiers() & (Qt::ShiftModifier | Qt::ControlModifier |
                                                 Qt::AltModifier | Qt::MetaModifier);
  // Shift counts only when it is not what types the symbol: "?" rather than "Shift+?", as the
  // defaults spell it. That is the form the shortcut map matches on X11 and Wayland: for Shift+/
  // their key mapper (QXkbCommon::possibleKeys) offers "Shift+/" and "?", never "Shift+?".
  const QString text = e->text();
  if ((mods & Qt::ShiftModifier) && !text.isEmpty() && text[0].isPrint() &&
      !text[0].isLetterOrNumber() && !text[0].isSpace())
    mods &= ~Qt::ShiftModifier;
  SetKeys(QKeySequence(QKeyCombination(mods, static_cast<Qt::Key>(key))));
}

void KeyBox::focusInEvent(QFocusEvent* e) {
  setPlaceholderText("press a key");
  QLineEdit::focusInEvent(e);
}

void KeyBox::focusOutEvent(QFocusEvent* e) {
  setPlaceholderText("none");
  QLineEdit::focusOutEvent(e);
}

ShortcutEditor::ShortcutEditor(std::vector<QAction*> actions, QWidget* parent) : QDialog(parent) {
  setWindowTitle("Change keyboard shortcuts");
  auto* layout = new QVBoxLayout(this);
  auto* hint = new QLabel(
      "To change a shortcut, click a key box and press the new key, with Ctrl, Shift or Alt if "
      "you like. An action can have two keys. <b>✕</b> clears a box; <b>Default</b> gives an "
      "action its original keys back. Changed actions are in <b>bold</b>. Nothing changes "
      "until you press OK.");
  hint->setWordWrap(true);
  layout->addWidget(hint);
  auto* find = new QLineEdit;
  find->setObjectName("find");
  find->setPlaceholderText("Find an action or a key…");
  find->setClearButtonEnabled(true);
  connect(find, &QLineEdit::textChanged, this, &ShortcutEditor::Filter);
  layout->addWidget(find);

  table_ = new QTableWidget(static_cast<int>(actions.size()), 3);
  table_->setHorizontalHeaderLabels({"Action", "Keys", ""});
  table_->verticalHeader()->setVisible(false);
  table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  table_->setSelectionMode(QAbstractItemView::NoSelection);
  table_->setFocusPolicy(Qt::NoFocus);
  table_->setTabKeyNavigation(false);
  rows_.resize(actions.size());
  for (int i = 0; i < rows(); ++i) {
    Row& r = rows_[i];
    r.action = actions[i];
    r.name = r.action->objectName().isEmpty() ? r.action->text() : r.action->objectName();
    const QList<QKeySequence> now = r.action->shortcuts();
    const QVariant defaults = r.action->property(kDefaultKeysProperty);
    r.default_text = defaults.isValid() ? defaults.toString() : Settings::JoinKeys(now);
    r.defaults = Settings::ParseKeys(r.default_text);
    r.extra = now.mid(2);

    r.item = new QTableWidgetItem(r.action->text());
    r.item->setToolTip("Default: " + Text(r.defaults));
    table_->setItem(i, 0, r.item);
    auto* keys = new QWidget;
    auto* row = new QHBoxLayout(keys);
    row->setContentsMargins(4, 2, 4, 2);
    r.first = new KeyBox;
    r.second = new KeyBox;
    r.first->SetKeys(now.value(0));
    r.second->SetKeys(now.value(1));
    row->addWidget(r.first, 1);
    row->addWidget(new QLabel("or"));
    row->addWidget(r.second, 1);
    table_->setCellWidget(i, 1, keys);
    r.reset = new QToolButton;
    r.reset->setText("Default");
    r.reset->setToolTip("Back to the default keys: " + Text(r.defaults));
    table_->setCellWidget(i, 2, r.reset);
    for (KeyBox* box : {r.first, r.second})
      connect(box, &KeyBox::KeysChanged, this, [this, i] {
        if (setting_) return;
        rows_[i].extra.clear();  // an edited row has the keys of its boxes, no more
        Refresh();
      });
    connect(r.reset, &QToolButton::clicked, this, [this, i] { ResetRow(i); });
  }
  table_->horizontalHeader()->setSectionResizeMode(0, QHeaderView::ResizeToContents);
  table_->horizontalHeader()->setSectionResizeMode(1, QHeaderView::Stretch);
  table_->horizontalHeader()->setSectionResizeMode(2, QHeaderView::ResizeToContents);
  table_->resizeRowsToContents();
  layout->addWidget(table_, 1);

  conflicts_ = new QLabel;
  conflicts_->setWordWrap(true);
  conflicts_->setStyleSheet("color: #a00000;");
  conflicts_->setVisible(false);
  layout->addWidget(conflicts_);

  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel);
  reset_all_ = buttons->addButton("Reset all to defaults", QDialogButtonBox::ResetRole);
  ok_ = buttons->button(QDialogButtonBox::Ok);
  for (QAbstractButton* b : buttons->buttons())  // no default button: see showEvent
    if (auto* push = qobject_cast<QPushButton*>(b)) push->setAutoDefault(false);
  connect(buttons, &QDialogButtonBox::accepted, this, &ShortcutEditor::accept);
  connect(buttons, &QDialogButtonBox::rejected, this, &ShortcutEditor::reject);
  connect(reset_all_, &QPushButton::clicked, this, &ShortcutEditor::ResetAll);
  layout->addWidget(buttons);
  resize(700, 760);
  Refresh();
}

void ShortcutEditor::showEvent(QShowEvent* e) {
  QDialog::showEvent(e);
  // No default button (the button box makes OK one when it is shown; the buttons are not
  // autoDefault, so the dialog does not pick another): Enter (after typing in the find box, say)
  // applies nothing, and no button looks as if it would.
  ok_->setDefault(false);
}

int ShortcutEditor::RowOf(const QString& name) const {
  for (int i = 0; i < rows(); ++i)
    if (rows_[i].name == name) return i;
  return -1;
}

QList<QKeySequence> ShortcutEditor::Keys(int row) const {
  const Row& r = rows_[row];
  QList<QKeySequence> keys;
  for (const QKeySequence& k : QList<QKeySequence>{r.first->keys(), r.second->keys()} + r.extra)
    if (!k.isEmpty() && !keys.contains(k)) keys.append(k);
  return keys;
}

QStringList ShortcutEditor::Conflicts() const { return conflict_lines_; }

void ShortcutEditor::SetRow(int row, const QList<QKeySequence>& keys) {
  Row& r = rows_[row];
  setting_ = true;
  r.first->SetKeys(keys.value(0));
  r.second->SetKeys(keys.value(1));
  r.extra = keys.mid(2);
  setting_ = false;
  Refresh();
}

void ShortcutEditor::ResetRow(int row) { SetRow(row, rows_[row].defaults); }

void ShortcutEditor::ResetAll() {
  for (int i = 0; i < rows(); ++i) SetRow(i, rows_[i].defaults);
}

void ShortcutEditor::Refresh() {
  // Which rows hold each key, in the order of the table.
  QList<QKeySequence> order;
  QHash<QKeySequence, QList<int>> on;
  for (int i = 0; i < rows(); ++i)
    for (const QKeySequence& k : Keys(i)) {
      if (!on.contains(k)) order.append(k);
      on[k].append(i);
    }
  conflict_lines_.clear();
  QSet<QKeySequence> shared;
  for (const QKeySequence& k : order) {
    const QList<int>& holders = on[k];
    if (holders.size() < 2) continue;
    shared.insert(k);
    QStringList names;
    for (int i : holders) names << Quoted(rows_[i].action->text());
    const QString last = names.takeLast();
    conflict_lines_ << QString("%1 is on %2%3 and %4")
                           .arg(Quoted(Text(k)), holders.size() == 2 ? "both " : "",
                                names.join(", "), last);
  }
  for (Row& r : rows_) {
    const int i = static_cast<int>(&r - rows_.data());
    const QList<QKeySequence> keys = Keys(i);
    r.conflict = false;
    for (const QKeySequence& k : keys) r.conflict = r.conflict || shared.contains(k);
    r.item->setBackground(r.conflict ? QBrush(QColor(255, 196, 196)) : QBrush());
    for (KeyBox* box : {r.first, r.second})
      box->setStyleSheet(shared.contains(box->keys()) ? kConflictStyle : "");
    const bool changed = keys != r.defaults;
    QFont font = r.item->font();
    font.setBold(changed);
    r.item->setFont(font);
    r.reset->setEnabled(changed);
  }
  if (conflict_lines_.isEmpty()) {
    conflicts_->clear();
    conflicts_->setVisible(false);
  } else {
    QString text =
        "<b>A key on two actions.</b> Change one of them; OK works again once every "
        "key is on one action only.";
    for (const QString& line : conflict_lines_) text += "<br>• " + line.toHtmlEscaped();
    conflicts_->setText(text);
    conflicts_->setVisible(true);
  }
  ok_->setEnabled(conflict_lines_.isEmpty());
}

void ShortcutEditor::Filter(const QString& text) {
  const QString want = text.trimmed();
  for (int i = 0; i < rows(); ++i) {
    const bool match = want.isEmpty() ||
                       rows_[i].action->text().contains(want, Qt::CaseInsensitive) ||
                       Text(Keys(i)).contains(want, Qt::CaseInsensitive);
    table_->setRowHidden(i, !match);
  }
}

void ShortcutEditor::accept() {
  Refresh();
  if (!conflict_lines_.isEmpty()) return;
  for (int i = 0; i < rows(); ++i) {
    const Row& r = rows_[i];
    const QList<QKeySequence> keys = Keys(i);
    if (keys != r.action->shortcuts()) r.action->setShortcuts(keys);
    Settings::SetShortcut(r.name, keys, r.default_text);
  }
  QDialog::accept();
}

}  // namespace netlab::gui
