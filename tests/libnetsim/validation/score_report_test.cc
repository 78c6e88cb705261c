#include "libnetsim/validation/score_report.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "common/hdf5_util.h"
#include "libnetsim/validation/score_file.h"
#include "tests/libnetsim/validation/score_test_data.h"

namespace netlab::netsim {
namespace {

using testing::ReadDoubles;

std::vector<double> Column(const std::vector<double>& v, int columns, int c) {
  std::vector<double> out;
  for (size_t i = c; i < v.size(); i += columns) out.push_back(v[i]);
  return out;
}

std::vector<double> ParseValues(const std::string& text) {
  std::vector<double> v;
  std::istringstream in(text);
  std::string word;
  while (in >> word) v.push_back(word == "nan" ? std::nan("") : std::stod(word));
  return v;
}

// The text of <svg id="id" ...> ... </svg>.
std::string Svg(const std::string& html, const std::string& id) {
  const size_t start = html.find("<svg id=\"" + id + "\"");
  if (start == std::string::npos) return "";
  return html.substr(start, html.find("</svg>", start) - start);
}

std::string Attribute(const std::string& element, const std::string& name) {
  std::smatch m;
  if (!std::regex_search(element, m, std::regex(" " + name + "=\"([^\"]*)\""))) return "";
  return m[1];
}

// The element (up to its '>') that carries data-series="name" in `svg`.
std::string Series(const std::string& svg, const std::string& name) {
  const size_t at = svg.find("data-series=\"" + name + "\"");
  if (at == std::string::npos) return "";
  const size_t open = svg.rfind('<', at);
  return svg.substr(open, svg.find('>', at) - open + 1);
}

// Values written with 9 significant digits: equal to the file's to 1e-8 relative, NaN to NaN.
void ExpectSameData(const std::vector<double>& plotted, const std::vector<double>& file,
                    const std::string& what) {
  ASSERT_EQ(plotted.size(), file.size()) << what;
  for (size_t i = 0; i < file.size(); ++i) {
    if (std::isnan(file[i])) {
      EXPECT_TRUE(std::isnan(plotted[i])) << what << " [" << i << "]";
    } else {
      EXPECT_NEAR(plotted[i], file[i], 1e-8 * std::abs(file[i]) + 1e-15)
          << what << " [" << i << "]";
    }
  }
}

// A path's vertices must be the finite values, placed by one increasing map of time to x and one
// decreasing (SVG y grows down) affine map of the value to y: the plot draws the data.
void ExpectPathDraws(const std::string& element, const std::vector<double>& times,
                     const std::vector<double>& values, double scale, const std::string& what) {
  const std::string d = Attribute(element, "d");
  std::regex vertex(R"([ML](-?[0-9.]+),(-?[0-9.]+))");
  std::vector<std::pair<double, double>> points;
  for (auto it = std::sregex_iterator(d.begin(), d.end(), vertex); it != std::sregex_iterator();
       ++it)
    points.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]));
  std::vector<double> t, v;
  for (size_t i = 0; i < values.size(); ++i)
    if (std::isfinite(values[i])) t.push_back(times[i]), v.push_back(values[i] * scale);
  ASSERT_EQ(points.size(), v.size()) << what;
  ASSERT_GE(v.size(), 3u) << what;
  // Least-squares lines y = a + b v and x = c + e t through the vertices: every vertex within
  // 0.1 px (written to 0.1 px), y decreasing with the value, x increasing with time.
  auto fit = [](const std::vector<double>& u, const std::vector<double>& w, double* a, double* b) {
    double su = 0, sw = 0, suu = 0, suw = 0;
    const double n = u.size();
    for (size_t i = 0; i < u.size(); ++i)
      su += u[i], sw += w[i], suu += u[i] * u[i], suw += u[i] * w[i];
    *b = (n * suw - su * sw) / (n * suu - su * su);
    *a = (sw - *b * su) / n;
  };
  std::vector<double> xs, ys;
  for (const auto& p : points) xs.push_back(p.first), ys.push_back(p.second);
  double a, b, c, e;
  fit(v, ys, &a, &b);
  fit(t, xs, &c, &e);
  EXPECT_LT(b, 0) << what;
  EXPECT_GT(e, 0) << what;
  for (size_t i = 0; i < v.size(); ++i) {
    EXPECT_NEAR(ys[i], a + b * v[i], 0.1) << what << " vertex " << i;
    EXPECT_NEAR(xs[i], c + e * t[i], 0.1) << what << " vertex " << i;
  }
}

class ScoreReport : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::ScratchDir("netlab_score_report");
    const ScoreResult result = testing::SmallScore();
    WriteScore((dir_ / "score.h5").string(), result);
    WriteScoreReport((dir_ / "report.html").string(), result,
                     {"tracks.h5", "sim.h5", (dir_ / "score.h5").string()});
    std::stringstream text;
    text << std::ifstream(dir_ / "report.html").rdbuf();
    html_ = text.str();
    file_ = h5::OpenFileReadOnly((dir_ / "score.h5").string());
  }
  void TearDown() override {
    file_ = h5::Id();
    std::filesystem::remove_all(dir_);
  }
  std::filesystem::path dir_;
  std::string html_;
  h5::Id file_;
};

TEST_F(ScoreReport, IsSelfContained) {
  EXPECT_EQ(html_.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(html_.find("</html>"), std::string::npos);
  for (const char* outside : {"<script", "src=", "href=", "http://", "https://"})
    EXPECT_EQ(html_.find(outside), std::string::npos) << outside;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "report.html.partial"));
}

TEST_F(ScoreReport, LeadsWithTheVerdictOfTheFile) {
  const std::string verdict = h5::ReadStringAttribute(file_.get(), "verdict");
  const size_t first_plot = html_.find("<svg");
  const size_t said =
      html_.find(verdict == "consistent" ? "<b>Consistent</b>" : "<b>Not consistent</b>");
  ASSERT_NE(said, std::string::npos);
  EXPECT_LT(said, first_plot);
}

TEST_F(ScoreReport, ErrorVsTimeHoldsTheRmsPerClassOfTheFile) {
  const std::string svg = Svg(html_, "error-vs-time");
  ASSERT_FALSE(svg.empty());
  const auto time = ReadDoubles(file_.get(), "/time");
  ExpectSameData(ParseValues(Attribute(svg, "data-times")), time, "times");
  const auto rms = ReadDoubles(file_.get(), "/error_vs_time/rms_m");
  const char* names[3] = {"corner", "edge", "inner"};
  for (int c = 0; c < 3; ++c) {
    const std::string path = Series(svg, names[c]);
    ASSERT_FALSE(path.empty()) << names[c];
    ExpectSameData(ParseValues(Attribute(path, "data-values")), Column(rms, 3, c), names[c]);
    ExpectPathDraws(path, time, Column(rms, 3, c), 1e3, names[c]);
  }
  // The masked corner makes a gap, not a line across it: two segments for the corners.
  const std::string corner = Attribute(Series(svg, "corner"), "d");
  EXPECT_EQ(std::count(corner.begin(), corner.end(), 'M'), 1);  // 3 corners still measured
}

TEST_F(ScoreReport, KnotMapHoldsEveryKnotsRmsOfTheFile) {
  const std::string svg = Svg(html_, "knot-map");
  ASSERT_FALSE(svg.empty());
  const auto rms = ReadDoubles(file_.get(), "/knots/rms_m");
  ExpectSameData(ParseValues(Attribute(svg, "data-values")), rms, "knot map");
  std::vector<int32_t> grid(2 * rms.size());
  h5::ReadDataset(file_.get(), "/knots/grid", H5T_NATIVE_INT32, grid.data());
  for (size_t k = 0; k < rms.size(); ++k) {
    const std::string key = "data-knot=\"(" + std::to_string(grid[2 * k]) + "," +
                            std::to_string(grid[2 * k + 1]) + ")\"";
    const size_t at = svg.find(key);
    ASSERT_NE(at, std::string::npos) << key;
    const std::string rect = svg.substr(at, svg.find('>', at) - at);
    EXPECT_NEAR(std::stod(Attribute(" " + rect, "data-value")), rms[k], 1e-8 * rms[k]) << key;
  }
}

TEST_F(ScoreReport, CornerAreaHoldsMeasuredAndSimulatedAreasOfTheFile) {
  const std::string svg = Svg(html_, "corner-area");
  ASSERT_FALSE(svg.empty());
  const auto time = ReadDoubles(file_.get(), "/time");
  for (const char* which : {"measured", "simulated"}) {
    const auto area = ReadDoubles(file_.get(), std::string("/global/corner_area_") + which);
    const std::string path = Series(svg, which);
    ExpectSameData(ParseValues(Attribute(path, "data-values")), area, which);
    ExpectPathDraws(path, time, area, 1.0, which);
  }
  // The measured area is missing while corner (5,5) is: frames 20..39.
  const auto measured = ReadDoubles(file_.get(), "/global/corner_area_measured");
  EXPECT_TRUE(std::isnan(measured[25]));
  const std::string d = Attribute(Series(svg, "measured"), "d");
  EXPECT_EQ(std::count(d.begin(), d.end(), 'M'), 2);
}

TEST_F(ScoreReport, D2HistogramHoldsTheCountsAndTheChi2ExpectationOfTheFile) {
  const std::string svg = Svg(html_, "d2-histogram");
  ASSERT_FALSE(svg.empty());
  const auto counts = ReadDoubles(file_.get(), "/d2_histogram/counts");
  const auto expected = ReadDoubles(file_.get(), "/d2_histogram/expected");
  ExpectSameData(ParseValues(Attribute(Series(svg, "counts"), "data-values")), counts, "counts");
  ExpectSameData(ParseValues(Attribute(Series(svg, "expected"), "data-values")), expected,
                 "expected");
  // One bar per bin, heights proportional to the counts.
  const size_t group = svg.find("data-series=\"counts\"");
  const std::string bars = svg.substr(group, svg.find("</g>", group) - group);
  std::regex bar(R"re(<rect [^>]*height="([0-9.]+)")re");
  std::vector<double> heights;
  for (auto it = std::sregex_iterator(bars.begin(), bars.end(), bar); it != std::sregex_iterator();
       ++it)
    heights.push_back(std::stod((*it)[1]));
  ASSERT_EQ(heights.size(), counts.size());
  const size_t top = std::max_element(counts.begin(), counts.end()) - counts.begin();
  for (size_t b = 0; b < counts.size(); ++b)
    EXPECT_NEAR(heights[b], heights[top] * counts[b] / counts[top], 0.15) << "bin " << b;
  // Both sum to the compared knot-frames.
  double n = 0, e = 0;
  for (size_t b = 0; b < counts.size(); ++b) n += counts[b], e += expected[b];
  EXPECT_NEAR(e, n, 1e-6 * n);
  EXPECT_EQ(n, ReadDoubles(file_.get(), "/per_class/points")[0] +
                   ReadDoubles(file_.get(), "/per_class/points")[1] +
                   ReadDoubles(file_.get(), "/per_class/points")[2]);
}

}  // namespace
}  // namespace netlab::netsim
