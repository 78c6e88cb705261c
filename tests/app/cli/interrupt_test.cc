// Ctrl+C stops a long command within about a second: it says "netlab NAME: cancelled" on stderr,
// exits 130, and leaves neither its output nor the output's "<out>.partial".

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

#include "tests/app/cli/run_netlab.h"
#include "tests/app/cli/small_shot.h"

namespace netlab::testing {
namespace {

struct Interrupted {
  bool ended_early = false;  // the command ended before the interrupt
  int status = -1;           // exit status; -1: killed by a signal (or not ended in time)
  double stop_s = 0.0;       // from SIGINT to the end
  std::string err;
};

class Interrupt : public CommandTest {
 protected:
  Interrupt() : CommandTest("interrupt") {}

  // Starts `netlab args` (stderr to a file), waits until `partial` appears (at most 10 s) and
  // `after_ms` more, sends SIGINT and waits at most 10 s for the end.
  Interrupted RunAndInterrupt(const std::string& args, const std::string& partial, int after_ms) {
    Interrupted r;
    const std::string err = Path("stderr.txt");
    const pid_t pid = fork();
    if (pid == 0) {
      execl("/bin/sh", "sh", "-c",
            ("exec " + std::string(NETLAB_EXE) + " " + args + " >/dev/null 2>" + err).c_str(),
            static_cast<char*>(nullptr));
      _exit(127);
    }
    using Clock = std::chrono::steady_clock;
    int status = 0;
    const auto start = Clock::now();
    while (!std::filesystem::exists(partial) && Clock::now() - start < std::chrono::seconds(10)) {
      if (waitpid(pid, &status, WNOHANG) == pid) {
        r.ended_early = true;
        return r;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(after_ms));
    kill(pid, SIGINT);
    const auto sent = Clock::now();
    bool ended = false;
    while (!(ended = waitpid(pid, &status, WNOHANG) == pid) &&
           Clock::now() - sent < std::chrono::seconds(10))
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (!ended) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return r;
    }
    r.stop_s = std::chrono::duration<double>(Clock::now() - sent).count();
    r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream in(err);
    std::stringstream text;
    text << in.rdbuf();
    r.err = text.str();
    return r;
  }

  // Stopped within 2 s with the message and status 130, neither `out` nor its partial left.
  static void ExpectCancelled(const Interrupted& r, const std::string& command,
                              const std::string& out) {
    ASSERT_FALSE(r.ended_early) << "netlab " << command << " ended before the interrupt";
    EXPECT_EQ(r.status, 130) << r.err;
    EXPECT_LT(r.stop_s, 2.0);
    EXPECT_NE(r.err.find("netlab " + command + ": cancelled\n"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out));
    EXPECT_FALSE(std::filesystem::exists(out + ".partial"));
  }

  // A 30 s flight of the small shot: minutes of work.
  std::string LongScenario() {
    std::string scene = kSmallShotScenario;
    scene.replace(scene.find("duration: 0.06"), 14, "duration: 30.0");
    std::ofstream(Path("long.yaml")) << scene;
    return Path("long.yaml");
  }
};

TEST_F(Interrupt, CtrlCStopsASimulationAndLeavesNoFile) {
  const std::string out = Path("sim.h5");
  const Interrupted r =
      RunAndInterrupt("simulate " + LongScenario() + " --out " + out, out + ".partial", 500);
  ExpectCancelled(r, "simulate", out);
}

TEST_F(Interrupt, CtrlCStopsASweepOnEveryThreadAndLeavesNoFile) {
  const std::string out = Path("sweep.h5");
  const Interrupted r = RunAndInterrupt("sweep " + LongScenario() +
                                            " --vary materials.nylon.bend_stiffness=5e-5:2e-4:4"
                                            " --jobs 2 --out " +
                                            out,
                                        out + ".partial", 500);
  ExpectCancelled(r, "sweep", out);
}

}  // namespace
}  // namespace netlab::testing
