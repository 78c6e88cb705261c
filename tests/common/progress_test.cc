// The progress type every long call takes: reports, a shared cancel token, the default reporter.

#include "common/progress.h"

#include <gtest/gtest.h>

#include <string>
#include <thread>
#include <vector>

namespace netlab {
namespace {

TEST(Progress, FractionIsDoneOverTotalClampedAndZeroWithoutATotal) {
  EXPECT_DOUBLE_EQ((Progress{"runs", 3.4, 12, ""}).fraction(), 3.4 / 12);
  EXPECT_DOUBLE_EQ((Progress{"runs", 13, 12, ""}).fraction(), 1.0);
  EXPECT_DOUBLE_EQ((Progress{"fit", 5, 0, ""}).fraction(), 0.0);
}

TEST(CancelToken, ACopyCancelsTheOriginalFromAnotherThread) {
  const CancelToken token;
  EXPECT_FALSE(token.cancelled());
  std::thread([copy = token] { copy.Cancel(); }).join();
  EXPECT_TRUE(token.cancelled());
  EXPECT_THROW(token.ThrowIfCancelled(), Cancelled);
  EXPECT_FALSE(CancelToken().cancelled()) << "a new token is a flag of its own";
}

TEST(ProgressReporter, TheDefaultReportsNothingAndNeverCancels) {
  const ProgressReporter none;
  EXPECT_FALSE(none.reports());
  none.Report("steps", 1, 2);  // goes nowhere
  EXPECT_FALSE(none.cancelled());
  EXPECT_NO_THROW(none.ThrowIfCancelled());
}

TEST(ProgressReporter, ReportsReachTheCallbackAndTheTokenStopsTheCall) {
  std::vector<Progress> seen;
  CancelToken cancel;
  const ProgressReporter reporter([&](const Progress& p) { seen.push_back(p); }, cancel);
  reporter.Report("frames", 1, 4, "cost 3");
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].stage, "frames");
  EXPECT_EQ(seen[0].done, 1);
  EXPECT_EQ(seen[0].total, 4);
  EXPECT_EQ(seen[0].detail, "cost 3");
  EXPECT_NO_THROW(reporter.ThrowIfCancelled());
  cancel.Cancel();
  EXPECT_TRUE(reporter.cancelled());
  EXPECT_THROW(reporter.ThrowIfCancelled(), Cancelled);
  EXPECT_STREQ(Cancelled().what(), "cancelled");
}

TEST(ProgressReporter, MappedAndSilentKeepTheToken) {
  std::vector<Progress> seen;
  CancelToken cancel;
  const ProgressReporter reporter([&](const Progress& p) { seen.push_back(p); }, cancel);
  const ProgressReporter part = reporter.Mapped([](Progress p) {
    p.done += 10;
    return p;
  });
  part.Report("runs", 1, 20);
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].done, 11);
  const ProgressReporter silent = reporter.Silent();
  silent.Report("runs", 2, 20);
  EXPECT_EQ(seen.size(), 1u);
  EXPECT_FALSE(silent.reports());
  cancel.Cancel();
  EXPECT_TRUE(part.cancelled());
  EXPECT_TRUE(silent.cancelled());
  EXPECT_FALSE(ProgressReporter().Mapped([](Progress p) { return p; }).reports());
}

}  // namespace
}  // namespace netlab
