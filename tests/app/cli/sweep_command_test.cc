// `netlab sweep` end to end, as a user runs it: every run is `netlab simulate --set` of its
// values bit for bit, a run that blows up is reported and the others kept, bad --vary arguments
// are errors naming them, the file is replaced only when complete, and under `mpirun -np 2` the
// ranks share the runs and give the same file.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/hdf5_util.h"
#include "common/tracks/track_file.h"
#include "tests/app/cli/run_netlab.h"

namespace {

using netlab::testing::Json;
using netlab::testing::LastJson;
using netlab::testing::NetlabResult;
using netlab::testing::RunNetlab;
namespace h5 = netlab::h5;

// 3 x 4 knots falling onto a sphere for 0.04 s at a fixed step: a few runs take a second.
constexpr char kNet[] = R"(name: small_net
duration: 0.04
output_interval: 0.005
integrator: {type: explicit, dt: 2.0e-5}
gravity: [0, 0, -9.81]
materials:
  pp: {diameter: 1.0e-3, linear_density: 7.1e-4, stretch_stiffness: 1178,
       bend_stiffness: 7.36e-5, twist_stiffness: 5.45e-5}
nets:
  - {name: net, material: pp, knots: [3, 4], mesh: 0.1, segments_per_link: 2, center: [0, 0, 0.2],
     corner_mass: 0.01, velocity: [0, 0, -1.0]}
bodies:
  - {name: ball, shape: sphere, center: [0, 0, 0], radius: 0.19}
)";

class SweepCommand : public netlab::testing::CommandTest {
 protected:
  SweepCommand() : CommandTest("sweep_command_test") {}
  void SetUp() override {
    CommandTest::SetUp();
    scenario_ = Path("net.yaml");
    std::ofstream(scenario_) << kNet;
  }
  std::string scenario_;
};

std::vector<double> ReadDoubles(const std::string& file, const std::string& name) {
  std::lock_guard<std::mutex> lock(h5::Mutex());
  h5::Id f = h5::OpenFileReadOnly(file);
  size_t n = 1;
  for (hsize_t d : h5::DatasetDims(f.get(), name)) n *= d;
  std::vector<double> v(n);
  h5::ReadDataset(f.get(), name, H5T_NATIVE_DOUBLE, v.data());
  return v;
}

std::vector<int> ReadInts(const std::string& file, const std::string& name) {
  std::lock_guard<std::mutex> lock(h5::Mutex());
  h5::Id f = h5::OpenFileReadOnly(file);
  size_t n = 1;
  for (hsize_t d : h5::DatasetDims(f.get(), name)) n *= d;
  std::vector<int> v(n);
  h5::ReadDataset(f.get(), name, H5T_NATIVE_INT, v.data());
  return v;
}

std::vector<std::string> ReadLines(const std::string& file, const std::string& name) {
  std::string text;
  {
    std::lock_guard<std::mutex> lock(h5::Mutex());
    h5::Id f = h5::OpenFileReadOnly(file);
    text = h5::ReadStringDataset(f.get(), name);
  }
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::string ReadText(const std::string& path) {
  std::stringstream s;
  s << std::ifstream(path).rdbuf();
  return s.str();
}

// Every run's knot tracks are those of `netlab simulate --set` with the run's overrides (as the
// file lists them), bit for bit; the JSON and the file agree on the values and the outputs.
TEST_F(SweepCommand, RunsMatchSingleSimulationsBitForBit) {
  const std::string out = Path("sweep.h5");
  const NetlabResult r = RunNetlab("sweep " + scenario_ +
                                   " --vary materials.pp.bend_stiffness=1e-4:3e-4:3"
                                   " --vary nets.0.corner_mass=0.01:0.02:2 --jobs 2 --out " +
                                   out + " --json --quiet");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json json = LastJson(r.out);
  EXPECT_EQ(json["runs"].number(), 6);
  EXPECT_EQ(json["failed"].number(), 0);
  EXPECT_EQ(json["jobs"].number(), 2);
  ASSERT_EQ(json["results"].array().size(), 6u);
  EXPECT_EQ(json["parameters"].array()[0]["path"].string(), "materials.pp.bend_stiffness");
  // Run 3: the second stiffness (index 1), the second corner mass (the last parameter fastest).
  EXPECT_EQ(json["results"].array()[3]["values"].array()[0].number(), 2e-4);
  EXPECT_EQ(json["results"].array()[3]["values"].array()[1].number(), 0.02);
  EXPECT_EQ(ReadDoubles(out, "runs/values"),
            (std::vector<double>{1e-4, 0.01, 1e-4, 0.02, 2e-4, 0.01, 2e-4, 0.02, 3e-4, 0.01, 3e-4,
                                 0.02}));
  const std::vector<std::string> overrides = ReadLines(out, "runs/overrides");
  ASSERT_EQ(overrides.size(), 6u);
  EXPECT_EQ(overrides[3], "--set materials.pp.bend_stiffness=2e-04 --set nets.0.corner_mass=0.02");
  const std::vector<double> penetration = ReadDoubles(out, "runs/max_penetration");
  for (int run : {0, 3, 5}) {
    const std::string single = Path("single" + std::to_string(run) + ".h5");
    const NetlabResult s = RunNetlab("simulate " + scenario_ + " " + overrides[run] + " --out " +
                                     single + " --json --quiet");
    ASSERT_EQ(s.status, 0) << s.err;
    const netlab::KnotTracks tracks = netlab::ReadKnotTracks(single);
    const std::string group = "tracks/" + std::to_string(run);
    EXPECT_EQ(ReadDoubles(out, group + "/time"), tracks.time);
    const std::vector<double> knots = ReadDoubles(out, group + "/knots/position");
    ASSERT_EQ(knots.size(), tracks.position.size() * 3);
    for (size_t k = 0; k < tracks.position.size(); ++k)
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(knots[3 * k + c], tracks.position[k][c]) << "run " << run << ", knot-frame " << k;
    // The same contact: the deepest penetration to the last bit (the JSON's to its 10 digits).
    EXPECT_GT(penetration[run], 0.0);
    EXPECT_NEAR(penetration[run], LastJson(s.out)["max_penetration"].number(),
                1e-9 * penetration[run]);
  }
  EXPECT_EQ(ReadInts(out, "runs/status"), std::vector<int>(6, 0));
  EXPECT_FALSE(std::filesystem::exists(out + ".partial"));
}

// A run that blows up (an absurd stiffness at the fixed step) is reported on stderr, in the JSON
// and in the file; the others are kept and the exit status is 0.
TEST_F(SweepCommand, BlowUpIsReportedAndTheOtherRunsKept) {
  const std::string out = Path("sweep.h5");
  const NetlabResult r =
      RunNetlab("sweep " + scenario_ + " --vary materials.pp.bend_stiffness=1e-4:1e4:2 --out " +
                out + " --json --set duration=0.02");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json json = LastJson(r.out);
  EXPECT_EQ(json["failed"].number(), 1);
  EXPECT_EQ(json["ok"].number(), 1);
  const Json& blown = json["results"].array()[1];
  EXPECT_EQ(blown["status"].string(), "blew up");
  EXPECT_NE(blown["error"].string().find("blew up at t = "), std::string::npos);
  EXPECT_TRUE(blown["max_area"].is_null());  // no output of a failed run, as in the file
  EXPECT_EQ(json["results"].array()[0]["status"].string(), "ok");
  EXPECT_NE(r.err.find("netlab sweep: run 1 (materials.pp.bend_stiffness=10000): simulation "
                       "blew up at t = "),
            std::string::npos)
      << r.err;
  // Progress on stderr (a line per 10 % where no terminal watches), then the summary.
  EXPECT_NE(r.err.find("sweep 100% 2/2 runs, 1 failed"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("sweep: 2 runs, 1 failed, in "), std::string::npos) << r.err;
  EXPECT_EQ(ReadInts(out, "runs/status"), (std::vector<int>{0, 1}));
  const std::vector<std::string> errors = ReadLines(out, "runs/errors");
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_EQ(errors[0], "");
  EXPECT_NE(errors[1].find("blew up at t = "), std::string::npos);
  EXPECT_TRUE(std::isnan(ReadDoubles(out, "runs/max_area")[1]));  // no output of a failed run
  EXPECT_EQ(ReadDoubles(out, "tracks/0/time").size(), 5u);        // the good run whole
  // The sensitivities need both runs: undefined, and the JSON says null.
  EXPECT_TRUE(json["sensitivity"]["max_area"].array()[0].is_null());
}

// A value the scenario rejects fails that run only, named with the value.
TEST_F(SweepCommand, BadParameterValueFailsOnlyItsRun) {
  const NetlabResult r =
      RunNetlab("sweep " + scenario_ + " --vary materials.pp.bend_stiffness=-1e-4:1e-4:2 --out " +
                Path("sweep.h5") + " --json --quiet --set duration=0.01");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json json = LastJson(r.out);
  EXPECT_EQ(json["results"].array()[0]["status"].string(), "bad value");
  EXPECT_NE(json["results"].array()[0]["error"].string().find("bend_stiffness: must be > 0"),
            std::string::npos);
  EXPECT_EQ(json["results"].array()[1]["status"].string(), "ok");
  EXPECT_NE(r.err.find("run 0 (materials.pp.bend_stiffness=-1e-04): bad value: "),
            std::string::npos)
      << r.err;
}

// Malformed --vary arguments are usage errors (status 2) naming the argument; an unknown path is
// the scenario's error (status 1) naming the --vary. Nothing is written, an existing file stays.
TEST_F(SweepCommand, BadVaryIsAnErrorNamingIt) {
  const std::string out = Path("sweep.h5");
  std::ofstream(out) << "the previous sweep";
  const std::string head = "sweep " + scenario_ + " --out " + out + " ";
  const struct {
    std::string vary;
    int status;
    std::string message;
  } cases[] = {
      {"materials.pp.bend_stiffness", 2,
       "--vary 'materials.pp.bend_stiffness': expected PATH=a:b:n"},
      {"materials.pp.bend_stiffness=1e-4:2e-4", 2, "expected a:b:n after '='"},
      {"materials.pp.bend_stiffness=1e-4:x:3", 2, "b = 'x' is not a number"},
      {"materials.pp.bend_stiffness=1e-4:2e-4:0", 2, "n = 0: need at least 1 value"},
      {"materials.nylon.bend_stiffness=1e-4:2e-4:2", 1,
       "--vary materials.nylon.bend_stiffness=1e-4:2e-4:2: 'materials.nylon' is not in the "
       "scenario (materials has: pp)"},
      {"nets.0.velocity=0:1:2", 1, "expected a list of 3 items as the scenario has there"},
  };
  for (const auto& c : cases) {
    const NetlabResult r = RunNetlab(head + "--vary '" + c.vary + "'");
    EXPECT_EQ(r.status, c.status) << c.vary << "\n" << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.vary << "\n" << r.err;
  }
  EXPECT_EQ(RunNetlab(head).status, 2);  // no --vary at all
  EXPECT_EQ(RunNetlab(head + "--vary duration=0.01:0.02:2 --jobs 0").status, 2);
  EXPECT_EQ(ReadText(out), "the previous sweep");
  EXPECT_FALSE(std::filesystem::exists(out + ".partial"));
}

// The file is written to sweep.h5.partial and renamed when complete: an output that cannot be
// created (its folder missing) fails before any run, and a finished sweep replaces the previous
// file whole.
TEST_F(SweepCommand, OutputIsReplacedOnlyWhenComplete) {
  const NetlabResult bad = RunNetlab("sweep " + scenario_ + " --vary duration=0.01:0.02:2 --out " +
                                     Path("no_such_dir/sweep.h5"));
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.err.find("--out " + Path("no_such_dir/sweep.h5") + ": the folder"),
            std::string::npos)
      << bad.err;
  EXPECT_NE(bad.err.find("no_such_dir does not exist"), std::string::npos) << bad.err;
  EXPECT_EQ(bad.err.find("run 0"), std::string::npos) << bad.err;  // before any run
  const std::string out = Path("sweep.h5");
  std::ofstream(out) << "the previous sweep";
  const NetlabResult r = RunNetlab("sweep " + scenario_ + " --vary duration=0.01:0.02:2 --out " +
                                   out + " --report " + Path("sweep.html") + " --quiet");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out + ".partial"));
  {
    std::lock_guard<std::mutex> lock(h5::Mutex());
    h5::Id f = h5::OpenFileReadOnly(out);
    EXPECT_EQ(h5::ReadStringAttribute(f.get(), "format"), "netlab-sweep");
    EXPECT_EQ(h5::ReadStringDataset(f.get(), "scenario"), kNet);
  }
  const std::string html = ReadText(Path("sweep.html"));
  EXPECT_NE(html.find("<h2>Against <code>duration</code></h2>"), std::string::npos);
  EXPECT_NE(html.find("<table id=\"sensitivity\">"), std::string::npos);
}

// Under `mpirun -np 2` the two ranks share the runs (rank 0 writes the file) and the file's
// tracks are those of a sweep in one process, bit for bit.
TEST_F(SweepCommand, MpirunSpreadsTheRunsOverTheRanks) {
#ifndef NETLAB_MPIEXEC
  GTEST_SKIP() << "netlab is built without MPI (install libopenmpi-dev openmpi-bin and "
                  "reconfigure): the mpirun case is not tested";
#else
  if (access(NETLAB_MPIEXEC, X_OK) != 0)
    GTEST_SKIP() << NETLAB_MPIEXEC << " is missing: the mpirun case is not tested";
  const std::string vary = " --vary materials.pp.bend_stiffness=1e-4:4e-4:4 --set duration=0.02";
  const std::string threads = Path("threads.h5"), ranks = Path("ranks.h5");
  const NetlabResult one =
      RunNetlab("sweep " + scenario_ + vary + " --out " + threads + " --quiet");
  ASSERT_EQ(one.status, 0) << one.err;
  // --oversubscribe: 2 ranks even where mpirun counts fewer slots; root (CI) must say so.
  // timeout: a launch that hangs (no shared memory in a container, say) fails the test in 2
  // minutes instead of holding ctest until its own limit.
  const std::string mpirun = "timeout 120 " + std::string(NETLAB_MPIEXEC) +
                             " -np 2 --oversubscribe" +
                             (geteuid() == 0 ? " --allow-run-as-root" : "") + " " + NETLAB_EXE;
  const std::string command = mpirun + " sweep " + scenario_ + vary + " --out " + ranks +
                              " --json --quiet 2>" + Path("mpi_err.txt");
  FILE* pipe = popen(command.c_str(), "r");
  std::string out;
  char buffer[4096];
  for (size_t n; (n = fread(buffer, 1, sizeof(buffer), pipe)) > 0;) out.append(buffer, n);
  const int status = WEXITSTATUS(pclose(pipe));
  ASSERT_EQ(status, 0) << ReadText(Path("mpi_err.txt"));
  const Json json = LastJson(out);  // printed once, by rank 0
  EXPECT_EQ(json["ranks"].number(), 2);
  EXPECT_EQ(json["runs"].number(), 4);
  EXPECT_EQ(json["failed"].number(), 0);
  const std::vector<int> rank = ReadInts(ranks, "runs/rank");
  EXPECT_EQ(rank.size(), 4u);
  EXPECT_NE(std::count(rank.begin(), rank.end(), 1), 0) << "rank 1 ran nothing";
  for (int run = 0; run < 4; ++run) {
    const std::string group = "tracks/" + std::to_string(run) + "/knots/position";
    EXPECT_EQ(ReadDoubles(ranks, group), ReadDoubles(threads, group)) << "run " << run;
  }
  EXPECT_EQ(ReadDoubles(ranks, "runs/max_area"), ReadDoubles(threads, "runs/max_area"));
#endif
}

TEST_F(SweepCommand, HelpDescribesTheCommand) {
  const NetlabResult r = RunNetlab("sweep --help");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("usage: netlab sweep SCENARIO.yaml --vary PATH=a:b:n"), std::string::npos);
  EXPECT_NE(r.out.find("--report FILE"), std::string::npos);
  EXPECT_NE(r.out.find("mpirun -np N netlab sweep"), std::string::npos);
  EXPECT_NE(RunNetlab("--help").out.find("sweep"), std::string::npos);
}

}  // namespace

namespace {

// The twin check of an ensemble: truth = the explicit step at 5e-6 s through the wrapping of the
// ball, model = the scenario's step. The runs of `sweep --ensemble` (step, segments per link,
// launch speed) give Sigma_sim: without it the model is rejected in the contact phase, with it
// consistent there.
TEST_F(SweepCommand, AnEnsembleMakesTheDefaultStepConsistentInContact) {
  const std::string set = " --set duration=0.2";
  const std::string ens = Path("ens.h5"), truth = Path("truth.h5"), model = Path("model.h5");
  NetlabResult r = RunNetlab("sweep " + scenario_ + set +
                             " --ensemble 8 --vary integrator.dt=1e-5:2.5e-5:4"
                             " --vary nets.0.segments_per_link=2:3:2"
                             " --vary nets.0.velocity.2=-1.005:-0.995:3 --out " +
                             ens + " --json --quiet");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(LastJson(r.out)["runs"].number(), 8);
  ASSERT_EQ(RunNetlab("simulate " + scenario_ + set + " --set integrator.dt=5e-6 --out " + truth +
                      " --quiet")
                .status,
            0);
  ASSERT_EQ(RunNetlab("simulate " + scenario_ + set + " --out " + model + " --quiet").status, 0);
  const std::string score = "score --measured " + truth + " --meas-sigma 1e-4 --sim " + model +
                            " --align none --out " + Path("score.h5") + " --json --quiet";
  auto contact = [](const Json& json) {
    for (const auto& phase : json["phases"].array())
      if (phase["name"].string() == "contact") return phase;
    ADD_FAILURE() << "no contact phase";
    return json["phases"].array()[0];
  };
  r = RunNetlab(score);
  ASSERT_EQ(r.status, 0) << r.err;
  Json json = LastJson(r.out);
  EXPECT_EQ(json["verdict"].string(), "inconsistent");
  EXPECT_EQ(json["ensemble_members"].number(), 0);
  EXPECT_GT(contact(json)["mean_d2"].number(), 30.0);
  EXPECT_EQ(contact(json)["sigma_sim_mm"].number(), 0.0);

  r = RunNetlab(score + " --sim-ensemble " + ens);
  ASSERT_EQ(r.status, 0) << r.err;
  json = LastJson(r.out);
  EXPECT_EQ(json["verdict"].string(), "consistent") << json["mean_d2"].number();
  EXPECT_EQ(json["ensemble_members"].number(), 8);
  EXPECT_LT(contact(json)["mean_d2"].number(), 4.0);
  EXPECT_GT(contact(json)["sigma_sim_mm"].number(), 0.1);
}

}  // namespace
