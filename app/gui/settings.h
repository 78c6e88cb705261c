#pragma once
// The workstation's settings (QSettings, organisation "netlab", application "netlab-gui"): the
// keys as named constants in one place, with their meaning.

#include <QSettings>
#include <QString>
#include <QStringList>

namespace netlab::gui {

class Settings {
 public:
  // The recent projects, most recent first (at most kMaxRecent).
  static constexpr char kRecentProjects[] = "recent_projects";
  static constexpr int kMaxRecent = 8;
  // A shortcut: "shortcuts/<action name>" holds its key sequence (QKeySequence::PortableText);
  // absent: the default of the action.
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
  static QString Shortcut(const QString& action, const QString& fallback) {
    return QSettings("netlab", "netlab-gui")
        .value(QString(kShortcutPrefix) + action, fallback)
        .toString();
  }
};

}  // namespace netlab::gui
