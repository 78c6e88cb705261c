// `netlab fit`'s engine on the digital twin: a small shot simulated with known parameters, its
// knots measured with 1 mm of seeded noise, fitted from a start off by a factor 2.

#include "libnetsim/identification/shot_fit.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "common/errors.h"
#include "libnetsim/sweep/sweep_runner.h"
#include "tests/libnetsim/identification/twin_shot.h"

namespace netlab::netsim {
namespace {

constexpr double kNoise = 1e-3;  // m

class ShotFit : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("shot_fit_test_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
    scenario_ = (dir_ / "shot.yaml").string();
    std::ofstream(scenario_) << testing::kTwinShot;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  KnotTracks Measured(uint32_t seed) const {
    const SweepRun truth = RunOne(scenario_, 0, {}, 1);
    EXPECT_TRUE(truth.ok()) << truth.error;
    return testing::MeasuredTwin(truth, kNoise, seed);
  }

  FitOptions Options(std::vector<ScenarioOverride> set) const {
    FitOptions o;
    o.set = std::move(set);
    o.score.meas_sigma_m = kNoise;
    o.jobs = 2;
    return o;
  }

  const FittedParameter& Find(const FitResult& r, const std::string& name) const {
    for (const FittedParameter& p : r.parameters)
      if (p.parameter.name == name) return p;
    ADD_FAILURE() << name << " is not in the result";
    return r.parameters.front();
  }

  std::filesystem::path dir_;
  std::string scenario_;
};

// Drag, launch velocity and launch time, from twice the drag and half the speed: each within 3
// of its reported sigmas of the truth, each identified, and the fit consistent with the noise.
TEST_F(ShotFit, RecoversDragLaunchAndTimeFromAStartOffByTwo) {
  const KnotTracks measured = Measured(7);
  // The starts, and a line no free parameter replaces (the twin's own integrator, named).
  const std::vector<ScenarioOverride> start = {{"drag.drag_coefficient", "2.4"},
                                               {"nets.0.velocity", "[0.25, 0, 0]"},
                                               {"integrator.type", "implicit"}};
  const auto parameters = ParseFreeParameters("drag.drag_coefficient,nets.0.velocity,time_offset",
                                              scenario_, start, 0.0);
  ASSERT_EQ(parameters.size(), 5u);
  const FitResult r = FitShot(scenario_, measured, parameters, Options(start));
  const std::vector<std::pair<std::string, double>> truth = {{"drag.drag_coefficient", 1.2},
                                                             {"nets.0.velocity.0", 0.5},
                                                             {"nets.0.velocity.1", 0.0},
                                                             {"nets.0.velocity.2", 0.0},
                                                             {"time_offset", 0.0}};
  for (const auto& [name, value] : truth) {
    const FittedParameter& p = Find(r, name);
    EXPECT_TRUE(std::isfinite(p.sigma) && p.sigma > 0) << name << " sigma " << p.sigma;
    EXPECT_LT(std::abs(p.value - value), 3 * p.sigma)
        << name << " = " << p.value << " +- " << p.sigma << ", truth " << value;
    EXPECT_TRUE(p.identified) << name;
    EXPECT_EQ(p.determined_by, DeterminedBy::kFlightData) << name;
  }
  // The cost is smooth in the drag: at -+ sigma it rises as the Jacobian predicts.
  const FittedParameter& drag = Find(r, "drag.drag_coefficient");
  EXPECT_FALSE(drag.rough);
  EXPECT_NEAR(drag.check[0], 1.0, 0.2);
  EXPECT_NEAR(drag.check[1], 1.0, 0.2);
  EXPECT_TRUE(std::isnan(Find(r, "time_offset").check[0]));  // alignment: not simulated
  // Tight, not merely honest: 1 mm noise on 25 knots over 0.4 s fixes the drag to about 2 %.
  EXPECT_LT(Find(r, "drag.drag_coefficient").sigma, 0.05);
  EXPECT_LT(r.cost_final, 1e-2 * r.cost_initial);
  EXPECT_EQ(r.score.verdict, Verdict::kConsistent) << "mean d2 " << r.score.mean_d2;
  EXPECT_NEAR(r.cost_final / r.residuals, 1.0, 0.1);  // whitened: about 1 per residual
  EXPECT_GT(r.simulations, 5);
  ASSERT_EQ(r.correlation.rows(), 5);
  EXPECT_NEAR(r.correlation(0, 0), 1.0, 1e-12);
  // The --set lines reproduce the fitted run: the user's line no estimate replaces (the start's
  // drag and whole velocity list are replaced), the estimates, the automatic step the fit held.
  ASSERT_EQ(r.fitted_set.size(), 6u);
  EXPECT_EQ(r.fitted_set[0].Text(), "integrator.type=implicit");
  EXPECT_EQ(r.fitted_set[1].path, "drag.drag_coefficient");
  EXPECT_NEAR(std::stod(r.fitted_set[1].value), Find(r, "drag.drag_coefficient").value, 1e-12);
  EXPECT_EQ(r.fitted_set[2].path, "nets.0.velocity.0");
  EXPECT_EQ(r.fitted_set[5].path, "integrator.dt");
  EXPECT_GT(r.dt_s, 0.0);
  EXPECT_EQ(std::stod(r.fitted_set[5].value), r.dt_s);
}

// The twist damping of a net in free flight leaves no trace the knots show: reported as not
// identified (its sigma the anchor's, ln 1000 = 6.9 times its value: not a confident number), and
// with a prior, as determined by the prior, its sigma the prior's.
TEST_F(ShotFit, SaysWhatTheFlightCannotDetermine) {
  const KnotTracks measured = Measured(11);
  const std::string free = "drag.drag_coefficient,materials.nylon.twist_damping";
  FitOptions options = Options({});
  std::vector<std::string> stages;
  std::vector<Progress> reports;
  options.progress = ProgressReporter([&](const Progress& p) {
    if (stages.empty() || stages.back() != p.stage) stages.push_back(p.stage);
    reports.push_back(p);
  });
  FitResult r =
      FitShot(scenario_, measured, ParseFreeParameters(free, scenario_, {}, 0.0), options);
  // The cost in a report's detail ("iteration 4, cost 812.3" or "cost 812.3").
  auto cost_of = [](const Progress& p) {
    const size_t at = p.detail.find("cost ");
    EXPECT_NE(at, std::string::npos) << p.detail;
    return at == std::string::npos ? 0.0 : std::stod(p.detail.substr(at + 5));
  };
  // The total bounds what the fit still ran, from the first report on (the scan found no second
  // valley here: nothing was added later), and it shrinks; the pace is known from the first
  // report (the start's simulation is done before it).
  ASSERT_FALSE(reports.empty());
  for (const Progress& p : reports) {
    EXPECT_GE(p.total, r.simulations) << p.stage << ", " << p.detail;
    EXPECT_GT(p.done, 0.0) << p.stage << ", " << p.detail;
  }
  // The cost reported is where the fit stands: it never rises within a stage (a rejected step's
  // cost is not reported), and the scan moves to its lowest point.
  for (size_t i = 1; i < reports.size(); ++i) {
    EXPECT_LE(reports[i].total, reports[i - 1].total)
        << reports[i].stage << ", " << reports[i].detail;
    if (reports[i].stage == reports[i - 1].stage) {
      EXPECT_LE(cost_of(reports[i]), cost_of(reports[i - 1]))
          << reports[i].stage << ", " << reports[i].detail;
    }
  }
  const FittedParameter& damping = Find(r, "materials.nylon.twist_damping");
  EXPECT_FALSE(damping.identified);
  EXPECT_EQ(damping.determined_by, DeterminedBy::kNeither);
  EXPECT_GT(damping.sigma, 5 * damping.value);
  EXPECT_TRUE(Find(r, "drag.drag_coefficient").identified);
  // The stages: the drag with the material held, the damping scanned, then both.
  const std::vector<std::string> expected = {
      "stage 1/3 material held", "stage 2/3 scan materials.nylon.twist_damping", "stage 3/3 all"};
  EXPECT_EQ(stages, expected);
  EXPECT_GE(r.ends, 1);

  FitOptions with_prior = Options({});
  with_prior.priors = {{"materials.nylon.twist_damping", 6e-11, 1e-11, "torsion.yaml"}};
  r = FitShot(scenario_, measured, ParseFreeParameters(free, scenario_, {}, 0.0), with_prior);
  const FittedParameter& informed = Find(r, "materials.nylon.twist_damping");
  EXPECT_FALSE(informed.identified);
  EXPECT_EQ(informed.determined_by, DeterminedBy::kPrior);
  EXPECT_TRUE(informed.has_prior);
  EXPECT_NEAR(informed.value, 6e-11, 1e-12);
  EXPECT_NEAR(informed.sigma, 1e-11, 1e-12);
}

// A free EI is noted when a net of its material has segments longer than 1.25 cm, with the count
// per link that brings them there (and, under the implicit step, the explicit one); not for
// another parameter, another material or fine links.
TEST_F(ShotFit, NotesLinksTooCoarseForTheBendingStiffness) {
  const auto notes = [&](const std::string& free, const std::vector<ScenarioOverride>& set) {
    return ResolutionNotes(LoadScenario(scenario_, set),
                           ParseFreeParameters(free, scenario_, set, 0.0), "shot.yaml");
  };
  const auto coarse = notes("drag.drag_coefficient,materials.nylon.bend_stiffness", {});
  ASSERT_EQ(coarse.size(), 1u);
  EXPECT_EQ(coarse[0].rfind("net 'net' of shot.yaml has 5 cm segments (2 per link)", 0), 0u)
      << coarse[0];
  EXPECT_NE(coarse[0].find("the fitted materials.nylon.bend_stiffness is this model's"),
            std::string::npos)
      << coarse[0];
  EXPECT_NE(coarse[0].find("--set nets.0.segments_per_link=8"), std::string::npos) << coarse[0];
  // The twin's implicit step hides EI whatever the links: the note says so, and not under explicit.
  EXPECT_NE(coarse[0].find("The implicit step hides most of EI's effect"), std::string::npos)
      << coarse[0];
  EXPECT_NE(coarse[0].find("--set integrator.type=explicit"), std::string::npos) << coarse[0];
  const auto explicit_step =
      notes("materials.nylon.bend_stiffness", {{"integrator.type", "explicit"}});
  ASSERT_EQ(explicit_step.size(), 1u);
  EXPECT_EQ(explicit_step[0].find("implicit"), std::string::npos) << explicit_step[0];
  EXPECT_TRUE(notes("materials.nylon.twist_stiffness,drag.drag_coefficient", {}).empty());
  EXPECT_TRUE(notes("materials.nylon.bend_stiffness", {{"nets.0.segments_per_link", "8"}}).empty());
  EXPECT_EQ(notes("materials.nylon.bend_stiffness", {{"nets.0.segments_per_link", "7"}}).size(),
            1u);
  // A long scenario path is kept whole, and the note ends as written.
  const std::string path(700, 'd');
  const auto long_note = ResolutionNotes(
      LoadScenario(scenario_, {}),
      ParseFreeParameters("materials.nylon.bend_stiffness", scenario_, {}, 0.0), path);
  ASSERT_EQ(long_note.size(), 1u);
  EXPECT_NE(long_note[0].find(" of " + path + " has "), std::string::npos);
  EXPECT_TRUE(long_note[0].ends_with("as a prior (--prior) to pick the valley")) << long_note[0];
}

// The scan's reading of a profile: the lowest point, and a second basin only behind a real
// barrier (a chi^2 rise of 9 above both), not the simulation's jitter or a failed run.
TEST(ScanMinima, ASecondBasinIsARivalJitterIsNot) {
  // One basin, jitter of 2 on its walls: no rival.
  ScanMinima m = FindScanMinima({50, 30, 32, 12, 5, 0, 4, 20, 18, 40}, 4);
  EXPECT_EQ(m.best, 5);
  EXPECT_EQ(m.rival, -1);
  // Net A's explicit profile along EI, in shape: a minimum at the scan's low end, a hump, the
  // truth's basin at the high end (the lower): each other's rival.
  const std::vector<double> two = {100, 110, 160, 210, 250, 240, 120, 20, 0, 30};
  m = FindScanMinima(two, 4);
  EXPECT_EQ(m.best, 8);
  EXPECT_EQ(m.rival, 0);
  // The barrier must rise 9 above both minima.
  m = FindScanMinima({10, 18, 0, 5}, 1);
  EXPECT_EQ(m.best, 2);
  EXPECT_EQ(m.rival, -1);
  m = FindScanMinima({8, 18, 0, 5}, 1);
  EXPECT_EQ(m.rival, 0);
  // Failed runs (NaN, inf) are never minima; the current point stays the best on a flat
  // profile.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  m = FindScanMinima({nan, 3, 3, 3, std::numeric_limits<double>::infinity()}, 2);
  EXPECT_EQ(m.best, 2);
  EXPECT_EQ(m.rival, -1);
  EXPECT_EQ(FindScanMinima({}, 0).best, -1);
}

// The scan looks a factor 2 either way of where the fit stands; with a prior, over the prior's
// reach (+-3 sigma about its value) when that is narrower, and never wider than a factor 2.
TEST(ScanCoordinates, APriorBoundsTheScanToItsReach) {
  FitParameter ea;
  ea.name = ea.path = "materials.nylon.stretch_stiffness";
  ea.log = true;
  const double current = std::log(3000.0);
  auto check = [](const std::vector<double>& along, double centre, double half) {
    ASSERT_EQ(along.size(), 17u);
    EXPECT_DOUBLE_EQ(along[8], centre);
    EXPECT_NEAR(along.front(), centre - half, 1e-12);
    EXPECT_NEAR(along.back(), centre + half, 1e-12);
    for (size_t k = 1; k < along.size(); ++k) EXPECT_GT(along[k], along[k - 1]);
  };
  check(ScanCoordinates(ea, nullptr, current, 8), current, std::log(2.0));
  // A bench's 5 % prior, off the start: the scan is centred on the prior, +-15 % in ln value.
  const FitPrior bench{ea.name, 1500.0, 75.0, "tensile.yaml"};
  check(ScanCoordinates(ea, &bench, current, 8), std::log(1500.0), 0.15);
  // A loose prior (50 %) reaches beyond a factor 2: the factor 2, about the prior.
  const FitPrior loose{ea.name, 1500.0, 750.0, "guess.yaml"};
  check(ScanCoordinates(ea, &loose, current, 8), std::log(1500.0), std::log(2.0));
  // A prior without a spread cannot bound anything: as without one.
  const FitPrior none{ea.name, 1500.0, 0.0, "broken.yaml"};
  check(ScanCoordinates(ea, &none, current, 8), current, std::log(2.0));
}

// The fit's ends after a scan found a second valley: one basin when every end is within 2 sigma
// of the estimate in the material parameters; another when any is beyond, whatever the others.
TEST(EndElsewhere, AnEndBeyondTwoSigmaInAMaterialIsAnotherBasin) {
  // drag, EA, EI (ln value); sigma of each
  const std::vector<double> best = {0.18, 7.37, -9.22}, sigma = {1e-4, 0.013, 0.011};
  const std::vector<bool> material = {false, true, true};
  // The rival's last stage came back (within 2 sigma).
  EXPECT_EQ(EndElsewhere({best, {0.18, 7.37 + 0.02, -9.22 - 0.015}}, best, sigma, material), -1);
  // Net A's explicit flight with a bench prior: a rival ended at EA 1137 N against 1591 +- 21.
  EXPECT_EQ(EndElsewhere({best, {0.18, std::log(1137.0), -9.22}}, best, sigma, material), 1);
  // Only EI elsewhere: still another basin.
  EXPECT_EQ(EndElsewhere({{0.18, 7.37, -9.0}, best}, best, sigma, material), 0);
  // Only the drag moved (not a material): the scan's valleys are the material's.
  EXPECT_EQ(EndElsewhere({{0.19, 7.37, -9.22}}, best, sigma, material), -1);
  // Infinite sigma (a direction the data leave free) never puts an end elsewhere.
  EXPECT_EQ(EndElsewhere({{0.18, 9.0, -9.22}}, best,
                         {1e-4, std::numeric_limits<double>::infinity(), 0.011}, material),
            -1);
}

// A fit that ends beyond its prior's reach says the flight and the bench disagree, naming the
// parameter, how far and the prior's source; within reach, or without a prior, nothing.
TEST(PriorConflict, AnEndBeyondThePriorsReachIsNoted) {
  FittedParameter f;
  f.parameter.name = "materials.nylon_1mm.stretch_stiffness";
  f.has_prior = true;
  f.prior_value = 1508.16;
  f.prior_sigma = 75.4;
  f.value = 2842.0;  // Net A: 4 segments per link fitted to a 16-segment flight
  const std::string note = PriorConflictNote(f, "bench.yaml (tensile test)");
  EXPECT_EQ(note.rfind("the fit puts materials.nylon_1mm.stretch_stiffness at 2842, 17.7 sigma "
                       "from its prior (1508 +- 75.4, bench.yaml (tensile test)): the flight "
                       "and the bench disagree",
                       0),
            0u)
      << note;
  f.value = 1508.16 - 3.1 * 75.4;
  EXPECT_NE(PriorConflictNote(f, "").find("-3.1 sigma from its prior (1508 +- 75.4)"),
            std::string::npos)
      << PriorConflictNote(f, "");
  const std::string source(700, 's');  // a long path, kept whole
  EXPECT_TRUE(PriorConflictNote(f, source).ends_with(", " + source +
                                                     "): the flight and the bench disagree. A "
                                                     "model coarser than the flight biases what "
                                                     "it fits (docs/fit.md, Limits), or the "
                                                     "bench did not measure this thread"));
  f.value = 1591.0;  // the explicit fit with a bench prior: 1.1 sigma
  EXPECT_TRUE(PriorConflictNote(f, "bench.yaml").empty());
  f.value = 1508.16 + 2.99 * 75.4;
  EXPECT_TRUE(PriorConflictNote(f, "bench.yaml").empty());
  f.value = 2842.0;
  f.has_prior = false;
  EXPECT_TRUE(PriorConflictNote(f, "bench.yaml").empty());
}

// End to end: a prior the flight contradicts (the drag's, 2.4 +- 0.05 where the flight has 1.2)
// is pulled far out of its reach, and the fit says so in its notes; a prior that agrees adds no
// note.
TEST_F(ShotFit, NotesAPriorTheFlightContradicts) {
  const KnotTracks measured = Measured(7);
  const auto parameters = ParseFreeParameters("drag.drag_coefficient", scenario_, {}, 0.0);
  FitOptions options = Options({});
  options.priors = {{"drag.drag_coefficient", 2.4, 0.05, "wind-tunnel.yaml"}};
  const FitResult off = FitShot(scenario_, measured, parameters, options);
  const FittedParameter& drag = Find(off, "drag.drag_coefficient");
  EXPECT_LT(drag.value, 2.4 - 3 * 0.05);  // the flight wins
  ASSERT_EQ(off.notes.size(), 1u);
  EXPECT_EQ(off.notes[0].rfind("the fit puts drag.drag_coefficient at ", 0), 0u) << off.notes[0];
  EXPECT_NE(off.notes[0].find("(2.4 +- 0.05, wind-tunnel.yaml)"), std::string::npos)
      << off.notes[0];
  options.priors = {{"drag.drag_coefficient", 1.2, 0.05, "wind-tunnel.yaml"}};
  const FitResult agrees = FitShot(scenario_, measured, parameters, options);
  EXPECT_TRUE(agrees.notes.empty()) << agrees.notes.front();
  EXPECT_TRUE(Find(agrees, "drag.drag_coefficient").identified);
}

// Two shots of the same net at 0.5 and 0.8 m/s: one drag for both, each shot its own launch; the
// drag twice as well known (about 1/sqrt(2) of one shot's sigma, or better: the faster shot feels
// more drag), every estimate within 3 sigma.
TEST_F(ShotFit, TwoShotsShareTheDragAndKeepTheirLaunches) {
  const std::string fast = (dir_ / "fast.yaml").string();
  std::string text = testing::kTwinShot;
  text.replace(text.find("velocity: [0.5, 0, 0]"), 21, "velocity: [0.8, 0, 0]");
  std::ofstream(fast) << text;
  const SweepRun truth_fast = RunOne(fast, 0, {}, 1);
  ASSERT_TRUE(truth_fast.ok()) << truth_fast.error;
  const KnotTracks slow_measured = Measured(7);
  const KnotTracks fast_measured = testing::MeasuredTwin(truth_fast, kNoise, 8);
  const std::vector<ScenarioOverride> start = {{"drag.drag_coefficient", "2.4"}};
  const std::string free = "drag.drag_coefficient,nets.0.velocity,time_offset";
  const auto both = ParseFreeParameters(free, std::vector<std::string>{scenario_, fast}, start, 0);
  ASSERT_EQ(both.size(), 9u);  // one drag, two launches of 3, two offsets
  EXPECT_EQ(both[0].shot, -1);
  EXPECT_EQ(both[4].name, "2:nets.0.velocity.0");
  EXPECT_EQ(both[4].path, "nets.0.velocity.0");
  const FitResult two = FitShots(
      {{scenario_, &slow_measured, "slow"}, {fast, &fast_measured, "fast"}}, both, Options(start));
  const FitResult one = FitShot(scenario_, slow_measured,
                                ParseFreeParameters(free, scenario_, start, 0), Options(start));
  const FittedParameter& drag = Find(two, "drag.drag_coefficient");
  EXPECT_LT(std::abs(drag.value - 1.2), 3 * drag.sigma) << drag.value << " +- " << drag.sigma;
  EXPECT_LT(drag.sigma, 0.8 * Find(one, "drag.drag_coefficient").sigma);
  const FittedParameter& v1 = Find(two, "1:nets.0.velocity.0");
  const FittedParameter& v2 = Find(two, "2:nets.0.velocity.0");
  EXPECT_LT(std::abs(v1.value - 0.5), 3 * v1.sigma);
  EXPECT_LT(std::abs(v2.value - 0.8), 3 * v2.sigma);
  ASSERT_EQ(two.scores.size(), 2u);
  EXPECT_EQ(two.scores[1].verdict, Verdict::kConsistent);
  // Each shot's --set lines: the shared drag, its own velocity, by the scenario's own paths.
  ASSERT_EQ(two.fitted_sets.size(), 2u);
  EXPECT_EQ(two.fitted_sets[1][1].path, "nets.0.velocity.0");
  EXPECT_NEAR(std::stod(two.fitted_sets[1][1].value), v2.value, 1e-12);
}

// --free's names: lists expand to their items, `frame` to 6, starts read after --set; what cannot
// be a parameter is named.
TEST_F(ShotFit, FreeParametersAreExpandedAndChecked) {
  const auto p = ParseFreeParameters("nets.0.velocity, frame,time_offset,drag.drag_coefficient",
                                     scenario_, {{"drag.drag_coefficient", "0.9"}}, 0.01);
  ASSERT_EQ(p.size(), 11u);
  EXPECT_EQ(p[1].name, "nets.0.velocity.1");
  EXPECT_EQ(p[3].name, "frame.wx");
  EXPECT_EQ(p[8].name, "frame.tz");
  EXPECT_EQ(p[9].kind, FitParameter::Kind::kTimeOffset);
  EXPECT_DOUBLE_EQ(p[9].start, 0.01);
  EXPECT_TRUE(p[10].log);
  EXPECT_DOUBLE_EQ(p[10].start, 0.9);
  EXPECT_NEAR(p[10].Value(p[10].Coordinate(0.9)), 0.9, 1e-15);
  const auto corners = ParseFreeParameters("nets.0.corner_velocities", scenario_, {}, 0.0);
  ASSERT_EQ(corners.size(), 12u);
  EXPECT_EQ(corners[5].name, "nets.0.corner_velocities.1.2");
  EXPECT_DOUBLE_EQ(corners[5].start, -0.05);

  const auto error_of = [&](const std::string& free, std::vector<ScenarioOverride> set = {}) {
    try {
      ParseFreeParameters(free, scenario_, set, 0.0);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of("materials.nylon.bend_stifness").find("bend_stifness"), std::string::npos);
  EXPECT_NE(error_of("materials.nylon").find("is a section"), std::string::npos);
  EXPECT_NE(error_of("nets.0.name").find("is not a number"), std::string::npos);
  EXPECT_NE(error_of("materials.nylon.twist_damping", {{"materials.nylon.twist_damping", "0"}})
                .find("must start positive"),
            std::string::npos);
  EXPECT_NE(error_of("time_offset,time_offset").find("named twice"), std::string::npos);
  EXPECT_NE(error_of("drag.drag_coefficient,,frame").find("empty name"), std::string::npos);
}

}  // namespace
}  // namespace netlab::netsim
