#include "libnetsim/characterization/damped_oscillator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace netlab::netsim {
namespace {

struct Series {
  std::vector<double> t, y;
};

Series Oscillation(double sigma, double omega, double noise, unsigned seed) {
  std::mt19937 engine(seed);
  std::normal_distribution<double> normal;
  Series s;
  for (int i = 0; i < 400; ++i) {
    const double t = 0.1 + 0.004 * i;
    s.t.push_back(t);
    s.y.push_back(0.3 + std::exp(-sigma * t) * 0.5 * std::cos(omega * t + 1.0) +
                  noise * normal(engine));
  }
  return s;
}

TEST(DampedOscillator, RecoversDecayAndFrequencyWithinTheirSigmas) {
  int outside = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const Series s = Oscillation(0.9, 88.0, 0.01, seed);
    OscillatorFit fit;
    std::string error;
    ASSERT_TRUE(FitDampedOscillator(s.t, s.y, &fit, &error)) << error;
    EXPECT_NEAR(fit.offset, 0.3, 0.01);
    EXPECT_NEAR(fit.amplitude(), 0.5 * std::exp(-0.9 * 0.1), 0.01);  // at the first sample
    EXPECT_NEAR(fit.rms, 0.01, 0.002);
    EXPECT_LT(fit.decay_rate_sigma, 0.1 * 0.9);
    outside += std::abs(fit.decay_rate - 0.9) > 2 * fit.decay_rate_sigma;
    outside += std::abs(fit.damped_frequency - 88.0) > 2 * fit.damped_frequency_sigma;
  }
  // 2 sigma holds for 95 % of the 40 estimates: a few may fall outside, not many.
  EXPECT_LE(outside, 6);
}

TEST(DampedOscillator, NaturalFrequencyAndDampingRatioFollowFromTheFit) {
  const Series s = Oscillation(2.0, 50.0, 0.0, 1);
  OscillatorFit fit;
  std::string error;
  ASSERT_TRUE(FitDampedOscillator(s.t, s.y, &fit, &error)) << error;
  EXPECT_NEAR(fit.natural_frequency(), std::sqrt(2.0 * 2.0 + 50.0 * 50.0), 1e-8);
  EXPECT_NEAR(fit.damping_ratio(), 2.0 / std::sqrt(2.0 * 2.0 + 50.0 * 50.0), 1e-10);
  EXPECT_NEAR(fit.Evaluate(s.t[123]), s.y[123], 1e-9);
}

TEST(DampedOscillator, ASeriesWithoutOscillationIsRefusedWithAReason) {
  std::vector<double> t, y;
  for (int i = 0; i < 100; ++i) t.push_back(0.01 * i), y.push_back(std::exp(-t.back()));
  OscillatorFit fit;
  std::string error;
  EXPECT_FALSE(FitDampedOscillator(t, y, &fit, &error));
  EXPECT_NE(error.find("no oscillation"), std::string::npos) << error;
}

}  // namespace
}  // namespace netlab::netsim
