#include "libnetsim/validation/summary_fields.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <stdexcept>
#include <string>

namespace netlab::netsim {
namespace {

// A summary with a value in every field the text summary shows.
ScoreSummary Example() {
  ScoreSummary s;
  s.frames = 40;
  s.knots = 121;
  s.points = 4001;
  s.masked = 839;
  s.alignment = Alignment::kTimeAndRigid;
  s.headline = "RMS 1.2 mm and largest 3.4 mm over all 4001 compared knot-frames";
  s.rms_m = 0.0012;
  s.rms_percent_of_side = 0.12;
  s.side_m = 1.0;
  s.per_class[0] = {"corner", 1, 0, 0.0018143};
  s.per_class[1] = {"edge", 1, 0, 0.0014992};
  s.per_class[2] = {"inner", 1, 0, 0.0012371};
  s.time_offset_s = 0.0027654;
  s.time_offset_sigma_s = 0.19672;
  s.sim_uncertainty = "zero";
  s.mean_d2 = 2.876e8;
  s.dof = 12002;
  s.effective_points = 19.5234;
  s.tau_int = 8.2461;
  s.design_effect = 24.861;
  s.p_value = 0;
  s.verdict = Verdict::kInconsistent;
  s.critical_mean_d2 = 4.4381;
  s.margin = -2.876e8;
  s.skill = 0.000317;
  s.baseline_rms_m = 1.3184;
  return s;
}

TEST(SummaryFields, KeysAreUniqueAndEveryFileFieldIsAScalarOrText) {
  std::set<std::string> keys;
  for (const SummaryField& field : SummaryFields()) {
    EXPECT_TRUE(keys.insert(std::string(field.key)).second) << field.key << " listed twice";
    EXPECT_NE(field.outputs, 0u) << field.key << " is printed nowhere";
    if (field.outputs & kInFile) {
      EXPECT_TRUE(field.kind == SummaryKind::kInt || field.kind == SummaryKind::kNumber ||
                  field.kind == SummaryKind::kText)
          << field.key << ": score.h5's /summary holds numbers and text only";
      if (field.kind != SummaryKind::kText) {
        EXPECT_FALSE(field.unit.empty()) << field.key << " has no units attribute";
      }
    }
  }
  EXPECT_EQ(FindSummaryField("rms_mm").value(Example()).number, 1.2);
  EXPECT_THROW(FindSummaryField("rms_m"), std::logic_error);
}

TEST(SummaryFields, TheTextSummaryIsFilledFromTheFields) {
  EXPECT_EQ(FillSummaryText("{points} of {frames}; [mean_d2], [p_value]\n", Example()),
            "4001 of 40; mean d2 2.876e+08, p = 0\n");
  EXPECT_EQ(FillSummaryText("[time_offset_s@ms] {time_offset_sigma_s@ms} ms\n", Example()),
            "time offset 2.765 196.7 ms\n");
  EXPECT_EQ(FillSummaryText("{per_class.edge} mm\n", Example()), "1.499 mm\n");
  EXPECT_THROW(FillSummaryText("{per_class.rim}", Example()), std::logic_error);
  EXPECT_THROW(FillSummaryText("{no_such_key}", Example()), std::logic_error);
  EXPECT_THROW(FillSummaryText("{frames", Example()), std::logic_error);
  EXPECT_THROW(FillSummaryText("{side_m@ms}", Example()), std::logic_error);
}

TEST(SummaryFields, ALinesFieldRepeatsItsLineAndLeavesItOutWhenEmpty) {
  ScoreSummary s = Example();
  EXPECT_EQ(FillSummaryText("a\n  [notes]\nb\n", s), "a\nb\n");
  s.notes = {"one", "two"};
  EXPECT_EQ(FillSummaryText("a\n  [notes]\nb\n", s), "a\n  note: one\n  note: two\nb\n");
}

TEST(SummaryFields, BriefReportKeepsItsLayout) {
  ScoreSummary s = Example();
  s.notes = {"Sigma_sim is zero"};
  EXPECT_EQ(s.BriefReport(),
            "score: 4001 knot-frames (40 frames x 121 knots, 839 masked), alignment time+rigid\n"
            "  RMS 1.2 mm and largest 3.4 mm over all 4001 compared knot-frames\n"
            "  RMS 0.12 % of the 1 m side; corner/edge/inner RMS 1.814 / 1.499 / 1.237 mm\n"
            "  time offset 2.765 +- 196.7 ms; Sigma_sim zero\n"
            "  mean d2 2.876e+08 (expected 3; dof 1.2e+04, effective points 19.52, tau_int 8.246 "
            "frames, design effect 24.86), p = 0\n"
            "  verdict: inconsistent with the measurement uncertainty (rejected above mean d2 "
            "4.438, margin -2.876e+08); skill 0.000317 against straight-line flight (1318 mm "
            "RMS)\n"
            "  note: Sigma_sim is zero\n");
}

}  // namespace
}  // namespace netlab::netsim
