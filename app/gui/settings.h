#pragma once
// The workstation's settings (QSettings, organisation "netlab", application "netlab-gui"): the
// keys as named constants in one place, with their meaning.

#include <QKeySequence>
#include <QList>
#include <QSettings>
#include <QString>
#include <QStringList>

namespace netlab::gui {

class Settings {
 public:
  // The recent projects, most recent first (at most kMaxRecent).
  static constexpr char kRecentProjects[] = "recent_projects";
  static constexpr int kMaxRecent = 8;
  // A shortcut: "shortcuts/<action name>" holds its key sequences (QKeySequence::PortableText,
  // several joined by ";", e.g. "F;Right"; "" for none); absent: the default of the action. The
  // window changes them in its shortcut editor (F1, "Change shortcuts…"), which removes the key
  // of an action whose keys equal its default again (so that a new default reaches the person).
  static constexpr char kShortcutPrefix[] = "shortcuts/";

  static QStringList RecentProjects() {
    return QSettings("netlab", "netlab-gui").value(kRecentProjects).toStringList();
  }
  static void AddRecentProject(const QString& path) {
    QSettings settings("netlab", "netlab-gui");
    QStringList recent = settings.value(kRecentProjects).toStringList();
    recent.removeAll(path);
    recent.prepend(path);
    while (recent.size() > kMaxRecent) recent.removeLast();
    settings.setValue(kRecentProjects, recent);
  }
  // Forgets `path` (a project that failed to open).
  static void RemoveRecentProject(const QString& path) {
    QSettings settings("netlab", "netlab-gui");
    QStringList recent = settings.value(kRecentProjects).toStringList();
    if (recent.removeAll(path) > 0) settings.setValue(kRecentProjects, recent);
  }
  static QString Shortcut(const QString& action, const QString& fallback) {
    return QSettings("netlab", "netlab-gui")
        .value(QString(kShortcutPrefix) + action, fallback)
        .toString();
  }
  // The key sequences of `action`: the settings' ones, else those of `default_keys` ("F;Right").
  static QList<QKeySequence> Shortcuts(const QString& action, const QString& default_keys) {
    return ParseKeys(Shortcut(action, default_keys));
  }
  // Stores the keys of `action`; keys equal to `default_keys` remove the setting instead.
  static void SetShortcut(const QString& action, const QList<QKeySequence>& keys,
                          const QString& default_keys) {
    if (keys == ParseKeys(default_keys))
      ResetShortcut(action);
    else
      QSettings("netlab", "netlab-gui").setValue(QString(kShortcutPrefix) + action, JoinKeys(keys));
  }
  // Forgets the stored keys of `action`: it has its default ones again.
  static void ResetShortcut(const QString& action) {
    QSettings("netlab", "netlab-gui").remove(QString(kShortcutPrefix) + action);
  }
  // Whether the settings hold keys of `action` (else it has its default ones).
  static bool HasShortcut(const QString& action) {
    return QSettings("netlab", "netlab-gui").contains(QString(kShortcutPrefix) + action);
  }

  // Key sequences <-> their settings text: PortableText joined by ";". A ";" that starts the
  // text, follows a separator or follows a modifier's "+" is the key ";" itself ("A;;" is A or
  // ";", "Ctrl+;" is Ctrl and ";"; "+;=" is still "+" or "="), so every key can be stored.
  static QList<QKeySequence> ParseKeys(const QString& text) {
    QList<QKeySequence> keys;
    QString part;
    const auto flush = [&] {
      const QString trimmed = part.trimmed();
      if (!trimmed.isEmpty()) {
        const QKeySequence k = QKeySequence::fromString(trimmed, QKeySequence::PortableText);
        if (!k.isEmpty()) keys.append(k);
      }
      part.clear();
    };
    for (const QChar c : text) {
      const QString sofar = part.trimmed();
      // "Ctrl+" waits for its key; "+" and "Ctrl++" are whole (the key "+").
      const bool waits = sofar.isEmpty() || (sofar.size() >= 2 && sofar.endsWith('+') &&
                                             sofar[sofar.size() - 2] != '+');
      if (c == ';' && !waits)
        flush();
      else
        part += c;
    }
    flush();
    return keys;
  }
  static QString JoinKeys(const QList<QKeySequence>& keys) {
    QStringList parts;
    for (const QKeySequence& k : keys) parts << k.toString(QKeySequence::PortableText);
    return parts.join(";");
  }
};

}  // namespace netlab::gui
