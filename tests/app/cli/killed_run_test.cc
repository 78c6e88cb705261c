// A run killed mid-way (SIGKILL: no handler, no cleanup; a full disk or an OOM kill looks the
// same) leaves the previous output exactly as it was and nothing half-written under its name
// (docs/bad_input.md): simulate, label and triangulate each write into "<out>.partial" and rename.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/labels/label_set.h"
#include "tests/app/cli/run_netlab.h"
#include "tests/app/cli/small_shot.h"

namespace netlab::testing {
namespace {

std::string Contents(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class KilledRun : public CommandTest {
 protected:
  KilledRun() : CommandTest("killed_run") {}

  // Starts `netlab args` (its output to /dev/null), waits until `out`.partial appears or
  // `wait_ms` pass, and kills it with SIGKILL. False if it ended on its own first.
  bool RunAndKill(const std::string& args, const std::string& out, int wait_ms) {
    const pid_t pid = fork();
    if (pid == 0) {
      execl("/bin/sh", "sh", "-c",
            ("exec " + std::string(NETLAB_EXE) + " " + args + " >/dev/null 2>&1").c_str(),
            static_cast<char*>(nullptr));
      _exit(127);
    }
    const auto start = std::chrono::steady_clock::now();
    int status = 0;
    while (std::chrono::steady_clock::now() - start < std::chrono::milliseconds(wait_ms)) {
      if (waitpid(pid, &status, WNOHANG) == pid) return false;
      if (std::filesystem::exists(out + ".partial")) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    return WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
  }

  // Kills `netlab args` mid-run with the previous output of the same command at `out`: it must
  // be byte for byte what it was, and be the only file under that name.
  void ExpectKillKeepsPrevious(const std::string& args, const std::string& out, int wait_ms) {
    const std::string before = Contents(out);
    ASSERT_FALSE(before.empty());
    ASSERT_TRUE(RunAndKill(args, out, wait_ms)) << "netlab " << args << " ended before the kill";
    EXPECT_EQ(Contents(out), before) << out << " changed";
    for (const auto& entry : std::filesystem::directory_iterator(dir_)) {
      const std::string name = entry.path().filename().string();
      const std::string base = std::filesystem::path(out).filename().string();
      if (name.rfind(base, 0) == 0) {
        EXPECT_TRUE(name == base || name == base + ".partial") << "left behind: " << name;
      }
    }
  }
};

TEST_F(KilledRun, SimulateKeepsThePreviousTracks) {
  std::string scene = kSmallShotScenario;
  std::ofstream(Path("short.yaml")) << scene;
  scene.replace(scene.find("duration: 0.06"), 14, "duration: 30.0");
  std::ofstream(Path("long.yaml")) << scene;
  ASSERT_EQ(
      RunNetlab("simulate " + Path("short.yaml") + " --out " + Path("sim.h5") + " --quiet").status,
      0);
  ExpectKillKeepsPrevious("simulate " + Path("long.yaml") + " --out " + Path("sim.h5"),
                          Path("sim.h5"), 3000);
}

TEST_F(KilledRun, TriangulateKeepsThePreviousTracks) {
  const calib::Rig rig = calib::PaperRig();
  calib::WriteRig(Path("rig.yaml"), rig);
  std::vector<std::string> names;
  for (const auto& c : rig.cameras) names.push_back(c.name);
  // 2000 frames of an 8 x 8 net: long enough to be killed in its bundle adjustment.
  constexpr int kFrames = 2000, kSide = 8;
  std::vector<int> frames;
  for (int t = 0; t < kFrames; ++t) frames.push_back(t);
  recon::LabelSet labels = recon::LabelSet::Empty(kSide, kSide, names, frames);
  for (int c = 0; c < 4; ++c)
    for (int t = 0; t < kFrames; ++t)
      for (int k = 0; k < kSide * kSide; ++k) {
        recon::Label& l = labels.at(c, t, k);
        const Eigen::Vector3d p(1.0 + 0.02 * t / 179.0, (k % kSide - 3.5) * 0.05,
                                (k / kSide - 3.5) * 0.05);
        l.px = rig.cameras[c].ProjectWorld(p);
        l.source = recon::LabelSource::kManual;
        l.confidence = 1.0f;
        l.state = recon::LabelState::kAccepted;
      }
  recon::WriteLabels(Path("labels.h5"), labels);
  const std::string base = "triangulate --rig " + Path("rig.yaml") + " --knots 8x8 --fps 179 " +
                           "--labels " + Path("labels.h5") + " --quiet --threads 1 ";
  const NetlabResult first = RunNetlab(base + "--ba none --out " + Path("t.h5"));
  ASSERT_EQ(first.status, 0) << first.err;
  ExpectKillKeepsPrevious(base + "--ba rig --smooth-sigma 0.001 --out " + Path("t.h5"),
                          Path("t.h5"), 1500);
}

TEST_F(KilledRun, LabelKeepsThePreviousLabels) {
  std::ofstream(Path("scenario.yaml")) << kSmallShotScenario;
  ASSERT_EQ(RunNetlab("simulate " + Path("scenario.yaml") + " --out " + Path("sim.h5") + " --quiet")
                .status,
            0);
  ASSERT_EQ(RunNetlab("color-net --knots 6x6 --out " + Path("coloring.yaml") + " --quiet").status,
            0);
  const NetlabResult render =
      RunNetlab("render --sim " + Path("sim.h5") + " --out " + Path("shot") +
                " --calibration-views 0 --coloring " + Path("coloring.yaml") + " --quiet");
  ASSERT_EQ(render.status, 0) << render.err;
  const std::string base = "label " + Path("shot/experiment.yaml") + " --rig " +
                           Path("shot/rig_true.yaml") + " --coloring " + Path("coloring.yaml") +
                           " --seed " + Path("shot/labels_true.h5") + " --quiet ";
  ASSERT_EQ(RunNetlab(base + "--frames 0:1 --out " + Path("labels.h5")).status, 0);
  ExpectKillKeepsPrevious(base + "--out " + Path("labels.h5"), Path("labels.h5"), 400);
}

}  // namespace
}  // namespace netlab::testing
