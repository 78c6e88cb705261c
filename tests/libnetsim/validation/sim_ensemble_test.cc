// The simulation's own spread from an ensemble (libnetsim/validation/sim_ensemble.h): a model that
// parts from the truth after "contact" as much as its own runs part from each other is rejected
// with Sigma_sim = 0 and consistent with the ensemble's spread; the ensemble is refused when it
// has one member, another net, or does not cover the simulation's time.

#include "libnetsim/validation/sim_ensemble.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "common/errors.h"
#include "libnetsim/validation/score.h"
#include "score_test_data.h"

namespace netlab::netsim {
namespace {

constexpr double kContact = 0.6;  // s: the deviations start here

// The truth plus a smooth deviation per knot that grows after kContact (a random direction and
// amplitude of about `size_m`, slowly turning): one run of a chaotic phase.
KnotTracks Chaotic(const KnotTracks& truth, double size_m, std::mt19937* rng) {
  KnotTracks out = truth;
  std::normal_distribution<double> normal(0.0, 1.0);
  const int knots = truth.knots();
  for (int k = 0; k < knots; ++k) {
    const Eigen::Vector3d a(normal(*rng), normal(*rng), normal(*rng));
    const Eigen::Vector3d b(normal(*rng), normal(*rng), normal(*rng));
    for (int f = 0; f < truth.frames(); ++f) {
      const double s = std::max(0.0, truth.time[f] - kContact) / 0.3;
      out.position[static_cast<size_t>(f) * knots + k] +=
          size_m * std::min(s, 1.0) * (std::cos(3 * s) * a + std::sin(3 * s) * b) / std::sqrt(2.0);
    }
  }
  return out;
}

struct Twin {
  KnotTracks measured, model;
  std::vector<EnsembleMember> members;
};

Twin MakeTwin(int members) {
  std::mt19937 rng(5);
  Twin twin;
  const KnotTracks truth = testing::SmallFlight(180, 0.0, 0.0, nullptr);
  twin.measured = Chaotic(truth, 0.02, &rng);  // the measured shot: one more chaotic draw
  std::normal_distribution<double> noise(0.0, 1e-3);
  for (size_t i = 0; i < twin.measured.position.size(); ++i) {
    twin.measured.position[i] += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    twin.measured.covariance.push_back(Eigen::Matrix3d::Identity() * 1e-6);
  }
  twin.model = Chaotic(truth, 0.02, &rng);
  for (int m = 0; m < members; ++m)
    twin.members.push_back({"member " + std::to_string(m), Chaotic(truth, 0.02, &rng)});
  return twin;
}

ScoreOptions Options() {
  ScoreOptions options;
  options.alignment = Alignment::kNone;
  options.contact_time_s = kContact;
  return options;
}

const ScoreRow& Phase(const ScoreSummary& s, const std::string& name) {
  for (const auto& row : s.per_phase)
    if (row.name == name) return row;
  ADD_FAILURE() << "no phase " << name;
  return s.per_phase.front();
}

TEST(SimEnsembleTest, TheSpreadMakesTheChaoticPhaseConsistent) {
  const Twin twin = MakeTwin(40);
  const ScoreResult bare = Score(twin.measured, twin.model, Options());
  EXPECT_EQ(bare.summary.verdict, Verdict::kInconsistent);
  EXPECT_GT(Phase(bare.summary, "contact").mean_d2, 50.0);
  EXPECT_EQ(Phase(bare.summary, "contact").sigma_sim_m, 0.0);

  double max_sigma = 0;
  const KnotTracks with = AddEnsembleCovariance(twin.model, "model", twin.members, &max_sigma);
  EXPECT_GT(max_sigma, 0.01);
  const ScoreResult scored = Score(twin.measured, with, Options());
  const ScoreRow& contact = Phase(scored.summary, "contact");
  EXPECT_EQ(scored.summary.verdict, Verdict::kConsistent) << scored.summary.mean_d2;
  EXPECT_LT(contact.mean_d2, 4.0);
  // Both contributions stated: the spread in contact is centimetres, before it nothing.
  EXPECT_GT(contact.sigma_sim_m, 0.01);
  EXPECT_NEAR(contact.sigma_meas_m, std::sqrt(3e-6), 1e-9);
  EXPECT_LT(Phase(scored.summary, "ejection").sigma_sim_m, 1e-9);
}

TEST(SimEnsembleTest, AWrongModelStaysRejectedBeforeTheChaos) {
  Twin twin = MakeTwin(40);
  // 5 mm off in every frame before contact: the spread there is zero, so nothing excuses it.
  for (int f = 0; f < twin.model.frames(); ++f)
    if (twin.model.time[f] < kContact)
      for (int k = 0; k < twin.model.knots(); ++k)
        twin.model.position[static_cast<size_t>(f) * twin.model.knots() + k].y() += 0.005;
  const KnotTracks with = AddEnsembleCovariance(twin.model, "model", twin.members);
  const ScoreResult scored = Score(twin.measured, with, Options());
  EXPECT_EQ(scored.summary.verdict, Verdict::kInconsistent);
  EXPECT_GT(Phase(scored.summary, "ejection").mean_d2, 20.0);
}

TEST(SimEnsembleTest, RefusesOneMemberAnotherNetAndAShortRun) {
  Twin twin = MakeTwin(2);
  std::vector<EnsembleMember> one = {twin.members[0]};
  try {
    AddEnsembleCovariance(twin.model, "sim.h5", one);
    FAIL() << "one member accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("at least 2 runs"), std::string::npos) << e.what();
  }
  std::vector<EnsembleMember> other = twin.members;
  other[1].tracks.grid[3] = {9, 9};
  try {
    AddEnsembleCovariance(twin.model, "sim.h5", other);
    FAIL() << "another net accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("member 1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("same net"), std::string::npos) << e.what();
  }
  std::vector<EnsembleMember> short_run = twin.members;
  KnotTracks& t = short_run[0].tracks;
  t.time.resize(90);
  t.position.resize(90 * t.knots());
  t.valid.resize(90 * t.knots());
  try {
    AddEnsembleCovariance(twin.model, "sim.h5", short_run);
    FAIL() << "a short run accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("member 0: covers"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace netlab::netsim
