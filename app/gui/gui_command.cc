// netlab gui [PROJECT.yaml [--room ROOM] [--frame N] [--review N] [--screenshot OUT.png
//            [--keys KEYS]]]
// netlab gui EXPERIMENT.yaml --rig RIG --labels LABELS [--coloring C] [--knots RxC] [--knotless]
//            [--project P]
#include "app/gui/gui_command.h"

#include <QAction>
#include <QApplication>
#include <QFileInfo>
#include <QImage>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>

#include "app/command_line/command_line.h"
#include "app/gui/document/project.h"
#include "app/gui/main_window.h"
#include "app/gui/settings.h"
#include "common/files.h"
#include "common/output_paths.h"
#include "common/yaml_util.h"

namespace netlab::gui {
namespace {

constexpr char kHelp[] =
    "usage: netlab gui [PROJECT.yaml] [--room ROOM] [--frame N] [--review N]\n"
    "                  [--screenshot OUT.png [--keys KEYS]]\n"
    "       netlab gui EXPERIMENT.yaml --rig rig.yaml --labels labels.h5 [--coloring C.yaml]\n"
    "                  [--knots RxC] [--knotless] [--target SIM.h5] [--project project.yaml]\n\n"
    "The workstation (docs/gui.md), in rooms: the recording (netlab ingest --check's findings\n"
    "per camera, the cameras' timestamps), the calibration (the rig, a 3D sketch of it), the\n"
    "labeling (four synchronized camera views, Find Node, Find Path, Fill Grid and tracking as\n"
    "undoable steps, the review queue, autosave with recovery), the reconstruction (3D\n"
    "tracks), the simulation (the simulated net drawn over the footage, netlab score's verdict).\n"
    "  netlab gui                  an empty window: File > Open / New project, recent projects\n"
    "  netlab gui PROJECT.yaml     opens a project (experiment, rig, colouring, labels, net)\n"
    "  netlab gui EXPERIMENT.yaml --room recording\n"
    "                              the recording alone, in the recording room (no rig or\n"
    "                              labels yet)\n"
    "  netlab gui EXPERIMENT.yaml --rig ... --labels ...\n"
    "                              makes a project of them (written to --project, default\n"
    "                              project.yaml beside the labels file) and opens it\n\n"
    "options:\n"
    "  --room ROOM         open in this room: recording, calibration, labeling (the default),\n"
    "                      reconstruction (the labels' 3D tracks) or simulation (the project's\n"
    "                      simulations scored against its tracks)\n"
    "  --frame N           open at frame number N\n"
    "  --review N          open at the N-th item of the review queue (as Space N times: its\n"
    "                      frame, its camera maximised, zoomed on the knot)\n"
    "  --screenshot FILE   draw the frame with its overlays, save the window as PNG and exit\n"
    "                      (works without a display)\n"
    "  --keys KEYS         with --screenshot: first press these keys of the window, separated\n"
    "                      by ';' (e.g. \"G\": a Fill Grid preview; \"M;E\"), and wait for what\n"
    "                      they start (not keys that open a dialog: F1, Ctrl+G, Ctrl+T, ...)\n"
    "  --rig, --labels, --coloring FILE, --knots RxC (without a colouring), --project FILE\n"
    "  --knotless          the net has no knot balls (Net B): an edge knot must lie where its\n"
    "                      straight links' colours change (the project's net: {knotless: true})\n"
    "  --target FILE       the target's bodies (a scenario, or a netlab simulate result) in the\n"
    "                      rig's world frame: the knots it hides are not listed as missing (the\n"
    "                      project's target:)\n\n"
    "Keys: F1 in the window lists them all. exit status: 0, 1 bad input, 2 usage error.\n";

bool IsProjectFile(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path);
  return root.IsMap() && root["netlab_project"];
}

// Why `path` (not a project) cannot be the experiment of a new project either, when the options
// that make one are missing: what the file holds, and the two ways it can be opened.
std::string NotAProject(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path);
  const std::string holds = root.IsNull()       ? "is empty"
                            : root.IsSequence() ? "holds a list, not a mapping of keys"
                            : root.IsScalar()   ? "holds a single value, not a mapping of keys"
                                                : "has no key netlab_project";
  return path + " " + holds +
         ": not a netlab project (a mapping with netlab_project: 1; docs/gui.md). To make a "
         "project of an experiment, give --rig and --labels with it; to check a recording "
         "alone, --room recording";
}

// Writes `image` to `path` through "<path>.partial" and a rename: `path` is either what it was
// or the whole image. False, with the reason on stderr, when it cannot.
bool SaveScreenshot(const QImage& image, const std::string& path) {
  const std::string partial = path + ".partial";
  QByteArray format = QFileInfo(QString::fromStdString(path)).suffix().toLower().toLatin1();
  if (format.isEmpty() || (format != "png" && format != "jpg" && format != "jpeg" &&
                           format != "bmp" && format != "ppm"))
    format = "png";
  if (!image.save(QString::fromStdString(partial), format.constData())) {
    std::filesystem::remove(partial);
    std::fprintf(stderr, "netlab gui: cannot write %s\n", partial.c_str());
    return false;
  }
  try {
    RenameInto(partial, path);
  } catch (const std::exception& e) {
    std::filesystem::remove(partial);
    std::fprintf(stderr, "netlab gui: %s\n", e.what());
    return false;
  }
  return true;
}

bool HasDisplay() {
  for (const char* name : {"DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM"}) {
    const char* value = std::getenv(name);
    if (value != nullptr && *value != '\0') return true;  // DISPLAY= is no display
  }
  return false;
}

// Triggers the window's actions bound to `keys` (Settings::ParseKeys: "G", "M;E"), one after
// the other, each once the work of the one before is done. False, saying which, for a key no
// action has.
bool PressKeys(MainWindow* window, const std::string& keys) {
  for (const QKeySequence& key : Settings::ParseKeys(QString::fromStdString(keys))) {
    QAction* bound = nullptr;
    for (QAction* a : window->actions())
      if (a->shortcuts().contains(key)) bound = a;
    if (bound == nullptr) {
      std::fprintf(stderr, "netlab gui: --keys: no action of the window has the key '%s'\n",
                   key.toString().toStdString().c_str());
      return false;
    }
    bound->trigger();
    if (!window->WaitForIdle())
      std::fprintf(stderr, "netlab gui: '%s' did not finish in time\n",
                   key.toString().toStdString().c_str());
  }
  return true;
}

}  // namespace

int RunGui(const std::vector<std::string>& args) {
  std::string project_path, experiment_path, screenshot, keys, room_name = "labeling";
  int frame = -1, review = 0;
  try {
    const app::CommandLine cl(args, {"help", "knotless"},
                              {"room", "frame", "review", "screenshot", "keys", "rig", "labels",
                               "coloring", "knots", "project", "target"});
    if (cl.Flag("help")) {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (cl.positional().size() > 1)
      throw app::UsageError("expected at most one project or experiment file");
    screenshot = cl.Option("screenshot").value_or("");
    keys = cl.Option("keys").value_or("");
    if (!keys.empty() && screenshot.empty()) throw app::UsageError("--keys needs --screenshot");
    room_name = cl.Option("room").value_or("labeling");
    if (room_name != "recording" && room_name != "calibration" && room_name != "labeling" &&
        room_name != "reconstruction" && room_name != "simulation")
      throw app::UsageError(
          "--room expects recording, calibration, labeling, reconstruction or simulation, got '" +
          room_name + "'");
    if (cl.Option("room") && cl.positional().empty())
      throw app::UsageError("--room needs a project");
    frame = cl.IntOption("frame", -1, 0, 100000000);
    review = cl.IntOption("review", 0, 1, 10000);
    if (!cl.positional().empty()) {
      const std::string& file = cl.positional()[0];
      if (IsProjectFile(file)) {
        project_path = file;
      } else if (room_name == "recording" && !cl.Option("rig") && !cl.Option("labels")) {
        experiment_path = file;  // a recording alone
        if (frame >= 0 || review > 0 || !keys.empty())
          throw app::UsageError("--frame, --review and --keys need a project, not a recording");
        CheckOutputPaths({{"experiment", experiment_path}}, {{"--screenshot", screenshot}});
      } else if (!cl.Option("rig") && !cl.Option("labels")) {
        throw std::runtime_error(NotAProject(file));
      } else {
        // An experiment: make its project first.
        int rows = 0, cols = 0;
        if (cl.Option("knots")) cl.Knots("knots", &rows, &cols);
        const std::string labels = cl.Required("labels");
        Project project = MakeProject(file, cl.Required("rig"), cl.Option("coloring").value_or(""),
                                      labels, rows, cols);
        project.knotless = cl.Flag("knotless");
        if (const auto target = cl.Option("target"))
          project.target = std::filesystem::absolute(*target).lexically_normal().string();
        project_path = cl.Option("project").value_or(
            (std::filesystem::absolute(labels).parent_path() / "project.yaml").string());
        SaveProject(project, project_path);
        std::fprintf(stderr, "netlab gui: wrote %s\n", project_path.c_str());
      }
    } else if (!screenshot.empty()) {
      throw app::UsageError("--screenshot needs a project");
    }
    if (!project_path.empty()) {
      // The project read before any window: a file that is no project says why here (exit 1),
      // and the screenshot never replaces the project or a file it names.
      const Project project = LoadProject(project_path);
      CheckOutputPaths({{"project", project_path},
                        {"experiment", project.experiment},
                        {"rig", project.rig},
                        {"coloring", project.coloring},
                        {"target", project.target},
                        {"labels", project.labels}},
                       {{"--screenshot", screenshot}});
    }
  } catch (const app::UsageError& e) {
    std::fprintf(stderr, "netlab gui: %s\n\n%s", e.what(), kHelp);
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "netlab gui: %s\n", e.what());
    return 1;
  }
  // A screenshot needs no screen; a window does.
  if (!screenshot.empty() && !HasDisplay()) setenv("QT_QPA_PLATFORM", "offscreen", 1);
  if (screenshot.empty() && !HasDisplay()) {
    std::fprintf(stderr,
                 "netlab gui: no display (DISPLAY is not set). Run it on a desktop, under "
                 "xvfb-run, or with --screenshot.\n");
    return 1;
  }
  int argc = 1;
  char name[] = "netlab";
  char* argv[] = {name, nullptr};
  QApplication app(argc, argv);
  QApplication::setOrganizationName("netlab");
  QApplication::setApplicationName("netlab-gui");
  MainWindow window;
  if (!experiment_path.empty()) {
    QString error;
    if (!window.OpenRecording(QString::fromStdString(experiment_path), &error)) {
      std::fprintf(stderr, "netlab gui: cannot open the recording: %s\n",
                   error.toLocal8Bit().constData());
      return 1;
    }
  }
  if (!project_path.empty()) {
    // A start that fails says why on stderr (and, in a window, in a dialog too); a screenshot
    // never waits on a dialog.
    QString error;
    if (!window.OpenProject(QString::fromStdString(project_path), screenshot.empty(), &error)) {
      std::fprintf(stderr, "netlab gui: cannot open the project: %s\n",
                   error.toLocal8Bit().constData());
      return 1;
    }
    if (frame >= 0) window.SetFrame(frame - window.session()->frame_number(0));
    for (int i = 0; i < review; ++i) window.NextReview();
    window.ShowRoom(room_name == "recording"        ? MainWindow::Room::kRecording
                    : room_name == "calibration"    ? MainWindow::Room::kCalibration
                    : room_name == "reconstruction" ? MainWindow::Room::kReconstruction
                    : room_name == "simulation"     ? MainWindow::Room::kSimulation
                                                    : MainWindow::Room::kLabeling);
  }
  if (!screenshot.empty()) {
    window.resize(1600, 1000);
    window.show();
    if (!project_path.empty() && !window.WaitForFrame())
      std::fprintf(stderr, "netlab gui: the frame did not load in time\n");
    if (!window.WaitForIdle())
      std::fprintf(stderr, "netlab gui: the room's work did not finish in time\n");
    if (!PressKeys(&window, keys)) return 2;
    // The layouts their results changed, settled as a person would see them (the preview
    // banner's second line was cut off in the screenshot, not in the window).
    QCoreApplication::processEvents();
    if (!SaveScreenshot(window.grab().toImage(), screenshot)) return 1;
    std::fprintf(stderr, "netlab gui: wrote %s\n", screenshot.c_str());
    return 0;
  }
  window.show();
  return QApplication::exec();
}

}  // namespace netlab::gui
