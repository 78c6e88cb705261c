// RunGuarded, the runner every subcommand's body goes through: what a body throws becomes the
// message on stderr and the exit status (docs/architecture.md, "Errors").

#include "app/command_line/command_line.h"

#include <gtest/gtest.h>

#include <csignal>
#include <new>
#include <stdexcept>
#include <string>

#include "common/errors.h"

namespace netlab::app {
namespace {

struct Outcome {
  int status;
  std::string err;
};

template <typename Body>
Outcome Guarded(Body body) {
  ::testing::internal::CaptureStderr();
  const int status = RunGuarded("demo", body);
  return {status, ::testing::internal::GetCapturedStderr()};
}

TEST(RunGuarded, PassesTheBodysStatusThroughAndSaysNothing) {
  const Outcome ok = Guarded([] { return 0; });
  EXPECT_EQ(ok.status, 0);
  EXPECT_EQ(ok.err, "");
  EXPECT_EQ(Guarded([] { return 1; }).status, 1);
}

TEST(RunGuarded, AUsageErrorPointsToHelpWithStatus2) {
  const Outcome r = Guarded([]() -> int { throw UsageError("--frames expects A:B, got '3'"); });
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, "netlab demo: --frames expects A:B, got '3'\n(see netlab demo --help)\n");
}

TEST(RunGuarded, AUsersInputIsAnErrorWithStatus1) {
  const Outcome r =
      Guarded([]() -> int { throw InputError("shot.yaml:4: key 'fps': not a number"); });
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.err, "netlab demo: error: shot.yaml:4: key 'fps': not a number\n");
  // A failed run (a file that cannot be written) and a library's check of the values it was
  // given read the same way.
  EXPECT_EQ(Guarded([]() -> int { throw std::runtime_error("out.h5: disk full"); }).err,
            "netlab demo: error: out.h5: disk full\n");
  for (const Outcome& given :
       {Guarded([]() -> int { throw std::invalid_argument("3 rows for 4 knots"); }),
        Guarded([]() -> int { throw std::out_of_range("stoi"); })})
    EXPECT_EQ(given.status, 1) << given.err;
}

TEST(RunGuarded, ACancelSaysCancelledWithStatus130) {
  const Outcome r = Guarded([]() -> int { throw Cancelled(); });
  EXPECT_EQ(r.status, kCancelledStatus);
  EXPECT_EQ(r.status, 130);
  EXPECT_EQ(r.err, "netlab demo: cancelled\n");
}

TEST(InterruptToken, SigintCancelsIt) {
  const CancelToken& token = InterruptToken();
  EXPECT_FALSE(token.cancelled());
  ASSERT_EQ(raise(SIGINT), 0);  // the handler sets the token; the process carries on
  EXPECT_TRUE(token.cancelled());
  EXPECT_TRUE(InterruptToken().cancelled()) << "one token for the process";
}

TEST(RunGuarded, ABrokenInvariantIsAnInternalErrorWithItsOwnStatus) {
  const Outcome r = Guarded([]() -> int { throw std::logic_error("AppendFrame after Commit"); });
  EXPECT_EQ(r.status, kInternalErrorStatus);
  EXPECT_NE(r.status, 1);
  EXPECT_NE(r.status, 2);
  EXPECT_EQ(r.err.rfind("netlab demo: internal error: AppendFrame after Commit\n", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("not a fault in the input"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("error: error"), std::string::npos);
}

TEST(RunGuarded, OutOfMemoryIsAFailedRunWithStatus1) {
  const Outcome r = Guarded([]() -> int { throw std::bad_alloc(); });
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.err.rfind("netlab demo: error: out of memory", 0), 0u) << r.err;
}

}  // namespace
}  // namespace netlab::app
