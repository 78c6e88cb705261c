#include "libreconstruct/labels/label_set.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <limits>
#include <mutex>
#include <numeric>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "common/hdf5_util.h"
#include "tests/libreconstruct/test_files.h"

namespace netlab::recon {
namespace {

using testing::ErrorOf;
using testing::Mentions;
using testing::ScratchDir;
using testing::WriteBytes;
namespace fs = std::filesystem;

constexpr int kRows = 3, kCols = 4, kFrames = 5;

// A 3 x 4 net seen by two cameras over five frames: every source and state value, confidences
// over 0..1, positions drawn with all 17 digits, and absent labels (NaN) every fifth. The cameras
// are not in name order, so a reader that took HDF5's (alphabetical) group order would show.
LabelSet Example(const std::vector<int>& frame_index = {10, 11, 12, 13, 14}) {
  LabelSet set = LabelSet::Empty(kRows, kCols, {"cam_right", "cam_left"}, frame_index);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> px(-50.0, 2000.0);
  for (int c = 0; c < 2; ++c)
    for (int t = 0; t < set.frames(); ++t)
      for (int k = 0; k < set.knots(); ++k) {
        const int i = (c * set.frames() + t) * set.knots() + k;
        if (i % 5 == 0) continue;
        Label& label = set.at(c, t, k);
        label.px = Eigen::Vector2d(px(rng), px(rng));
        label.source = static_cast<LabelSource>(i % 9);  // every source, kProjected too
        label.state = static_cast<LabelState>(i % 3);
        label.confidence = static_cast<float>(i % 11) / 10.0f;
      }
  return set;
}

bool SameDouble(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

// Equal in every field, bit for bit; NaN positions match NaN.
::testing::AssertionResult SameLabels(const LabelSet& a, const LabelSet& b) {
  if (a.rows != b.rows || a.cols != b.cols)
    return ::testing::AssertionFailure()
           << "shape " << a.rows << "x" << a.cols << " vs " << b.rows << "x" << b.cols;
  if (a.cameras != b.cameras) return ::testing::AssertionFailure() << "camera names differ";
  if (a.frame_index != b.frame_index) return ::testing::AssertionFailure() << "frames differ";
  if (a.labels.size() != b.labels.size())
    return ::testing::AssertionFailure() << "camera count differs";
  for (size_t c = 0; c < a.labels.size(); ++c) {
    if (a.labels[c].size() != b.labels[c].size())
      return ::testing::AssertionFailure() << "camera " << c << ": label count differs";
    for (size_t i = 0; i < a.labels[c].size(); ++i) {
      const Label &x = a.labels[c][i], &y = b.labels[c][i];
      if (!SameDouble(x.px.x(), y.px.x()) || !SameDouble(x.px.y(), y.px.y()) ||
          x.source != y.source || x.state != y.state || x.confidence != y.confidence)
        return ::testing::AssertionFailure()
               << "camera " << c << " label " << i << ": (" << x.px.transpose() << ") vs ("
               << y.px.transpose() << ")";
    }
  }
  return ::testing::AssertionSuccess();
}

// Edits a written labels file in place with the raw HDF5 API, to break it in one way.
void EditFile(const std::string& path, const std::function<void(hid_t)>& edit) {
  std::lock_guard<std::mutex> lock(h5::Mutex());
  h5::Id file = h5::OpenFileReadWrite(path);
  edit(file.get());
}

// Replaces dataset `name` by one of shape `dims`, stored as `type`, holding `value` everywhere.
void ReplaceDataset(hid_t file, const std::string& name, hid_t type,
                    const std::vector<hsize_t>& dims, double value = 0.0) {
  ASSERT_GE(H5Ldelete(file, name.c_str(), H5P_DEFAULT), 0) << name;
  const size_t n = std::accumulate(dims.begin(), dims.end(), size_t{1}, std::multiplies<>());
  const std::vector<double> values(n, value);
  h5::Id space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr));
  h5::Id dataset(
      H5Dcreate2(file, name.c_str(), type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  ASSERT_TRUE(dataset.valid()) << name;
  ASSERT_GE(
      H5Dwrite(dataset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
}

// Sets element `index` (flat) of an existing uint8 dataset.
void SetByte(hid_t file, const std::string& name, size_t index, uint8_t value) {
  const std::vector<hsize_t> dims = h5::DatasetDims(file, name);
  const size_t n = std::accumulate(dims.begin(), dims.end(), size_t{1}, std::multiplies<>());
  std::vector<uint8_t> data(n);
  h5::ReadDataset(file, name, H5T_NATIVE_UINT8, data.data());
  data.at(index) = value;
  h5::Id dataset(H5Dopen2(file, name.c_str(), H5P_DEFAULT));
  ASSERT_GE(H5Dwrite(dataset.get(), H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()),
            0);
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> Split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, separator)) parts.push_back(part);
  return parts;
}

// ---------------------------------------------------------------------------------------------
// LabelSet

TEST(LabelSet, EmptyHasEveryLabelAbsent) {
  const LabelSet set = LabelSet::Empty(2, 3, {"a", "b"}, {4, 5, 6, 7});
  EXPECT_EQ(set.knots(), 6);
  EXPECT_EQ(set.frames(), 4);
  ASSERT_EQ(set.labels.size(), 2u);
  EXPECT_EQ(set.labels[1].size(), 24u);
  EXPECT_EQ(set.CountPresent(), 0);
  EXPECT_EQ(set.at(1, 3, 5).source, LabelSource::kNone);
}

TEST(LabelSet, SameLabelComparesEveryFieldAndTakesAbsentPositionsAlike) {
  const Label absent;
  EXPECT_TRUE(SameLabel(absent, Label()));  // NaN positions: both absent
  Label placed;
  placed.px = {10.5, 20.25};
  placed.source = LabelSource::kManual;
  placed.confidence = 1.0f;
  placed.state = LabelState::kAccepted;
  EXPECT_TRUE(SameLabel(placed, placed));
  EXPECT_FALSE(SameLabel(placed, absent));
  for (int field = 0; field < 4; ++field) {
    Label other = placed;
    if (field == 0) other.px.y() = 20.5;
    if (field == 1) other.source = LabelSource::kNone;
    if (field == 2) other.confidence = 0.5f;
    if (field == 3) other.state = LabelState::kNeedsReview;
    EXPECT_FALSE(SameLabel(placed, other)) << "field " << field;
  }
  EXPECT_FALSE(SameLabel(Label::Hidden(), absent));  // hidden: the person's mark, no position
}

TEST(LabelSet, FindsCamerasByName) {
  const LabelSet set = LabelSet::Empty(1, 1, {"left", "right"}, {0});
  EXPECT_EQ(set.FindCamera("left"), 0);
  EXPECT_EQ(set.FindCamera("right"), 1);
  EXPECT_EQ(set.FindCamera("centre"), -1);
}

TEST(LabelSet, CountsOnlyLabelsWithBothCoordinatesFinite) {
  LabelSet set = LabelSet::Empty(2, 2, {"a", "b"}, {0, 1});
  set.at(0, 0, 0).px = Eigen::Vector2d(1.0, 2.0);
  set.at(1, 1, 3).px = Eigen::Vector2d(0.0, 0.0);
  set.at(1, 0, 2).px = Eigen::Vector2d(5.0, std::nan(""));
  set.at(0, 1, 1).px = Eigen::Vector2d(std::numeric_limits<double>::infinity(), 1.0);
  EXPECT_EQ(set.CountPresent(), 2);
  EXPECT_EQ(Example().CountPresent(), 2 * kFrames * kRows * kCols * 4 / 5);
}

// ---------------------------------------------------------------------------------------------
// labels.h5

TEST(LabelsFile, RoundTripKeepsEveryFieldExactly) {
  ScratchDir dir("labels");
  const LabelSet written = Example();
  WriteLabels(dir / "labels.h5", written);
  const LabelSet read = ReadLabels(dir / "labels.h5");
  EXPECT_TRUE(SameLabels(read, written));
  EXPECT_EQ(read.cameras, (std::vector<std::string>{"cam_right", "cam_left"}));
  EXPECT_TRUE(std::isnan(read.at(0, 0, 0).px.x()));
}

// The person's "not visible here" (LabelState::kHidden, no position) survives a save: a file
// without hidden marks reads as before (the test above), one with them keeps them exactly.
TEST(LabelsFile, HiddenMarksRoundTripWithoutAPosition) {
  ScratchDir dir("labels");
  LabelSet written = Example();
  written.at(0, 1, 5) = Label::Hidden();  // over a present label
  written.at(1, 0, 0) = Label::Hidden();  // over an absent one
  WriteLabels(dir / "labels.h5", written);
  const LabelSet read = ReadLabels(dir / "labels.h5");
  EXPECT_TRUE(SameLabels(read, written));
  EXPECT_TRUE(read.at(0, 1, 5).hidden());
  EXPECT_FALSE(read.at(0, 1, 5).present());
  EXPECT_TRUE(read.at(1, 0, 0).hidden());
  EXPECT_EQ(read.CountPresent(), written.CountPresent());
}

// A hidden mark with a position contradicts itself: refused by name, on reading and on writing.
TEST(LabelsFile, AHiddenMarkWithAPositionIsNamed) {
  ScratchDir dir("labels");
  const std::string path = dir / "labels.h5";
  // Row 2, knot 7 (flat index 31) of cam_right holds a position in Example().
  WriteLabels(path, Example());
  EditFile(path, [](hid_t f) { SetByte(f, "/cameras/cam_right/state", 31, 3); });
  EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabels(path); }),
                       {"/cameras/cam_right/state", "hidden", "row 2, knot 7", "position_px"}));
  LabelSet set = Example();
  set.at(0, 2, 7).state = LabelState::kHidden;
  EXPECT_THROW(WriteLabels(dir / "other.h5", set), std::invalid_argument);
}

TEST(LabelsFile, ReviewReasonsRoundTripAsOneLineEach) {
  ScratchDir dir("labels");
  LabelSet written = Example();
  written.reasons[{1, 4, 2}] = "moved 2.1 px otherwise than its neighbours";
  written.reasons[{0, 0, 0}] = "two\tlines\nin one";  // tabs and breaks become spaces
  WriteLabels(dir / "labels.h5", written);
  const LabelSet read = ReadLabels(dir / "labels.h5");
  EXPECT_EQ(read.reasons.size(), 2u);
  EXPECT_EQ(read.reasons.at({1, 4, 2}), "moved 2.1 px otherwise than its neighbours");
  EXPECT_EQ(read.reasons.at({0, 0, 0}), "two lines in one");
  // A file without reasons (every file before them) reads with none.
  WriteLabels(dir / "plain.h5", Example());
  EXPECT_TRUE(ReadLabels(dir / "plain.h5").reasons.empty());
}

// Written by another tool as a variable-length string (h5py's default for str): read as its
// text, not as the bytes of a pointer; a reason line that is wrong is quoted as written.
TEST(LabelsFile, ReviewReasonsAsAVariableLengthStringAreReadAsText) {
  ScratchDir dir("labels");
  WriteLabels(dir / "labels.h5", Example());
  const auto write_vlen = [](hid_t f, const std::string& text) {
    H5Ldelete(f, "review_reasons", H5P_DEFAULT);
    h5::Id type(H5Tcopy(H5T_C_S1));
    H5Tset_size(type.get(), H5T_VARIABLE);
    H5Tset_cset(type.get(), H5T_CSET_UTF8);
    h5::Id space(H5Screate(H5S_SCALAR));
    h5::Id dataset(H5Dcreate2(f, "review_reasons", type.get(), space.get(), H5P_DEFAULT,
                              H5P_DEFAULT, H5P_DEFAULT));
    const char* data = text.c_str();
    H5Dwrite(dataset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &data);
  };
  EditFile(dir / "labels.h5", [&](hid_t f) {
    write_vlen(f, "1\t4\t2\tmoved 2.1 px otherwise than its neighbours\n");
  });
  EXPECT_EQ(ReadLabels(dir / "labels.h5").reasons.at({1, 4, 2}),
            "moved 2.1 px otherwise than its neighbours");
  EditFile(dir / "labels.h5", [&](hid_t f) { write_vlen(f, "9 9 9 out of the set\n"); });
  const std::string error = ErrorOf([&] { ReadLabels(dir / "labels.h5"); });
  EXPECT_NE(error.find("/review_reasons line 1"), std::string::npos) << error;
  EXPECT_NE(error.find("9 9 9 out of the set"), std::string::npos) << error;
}

TEST(LabelsFile, RoundTripOfNoFramesAndNoCameras) {
  ScratchDir dir("labels");
  for (const LabelSet& written :
       {LabelSet::Empty(2, 2, {"a", "b"}, {}), LabelSet::Empty(2, 2, {}, {0, 1, 2})}) {
    WriteLabels(dir / "labels.h5", written);
    EXPECT_TRUE(SameLabels(ReadLabels(dir / "labels.h5"), written));
  }
}

TEST(LabelsFile, LeavesNoPartialFileBehind) {
  ScratchDir dir("labels");
  WriteLabels(dir / "labels.h5", Example());
  EXPECT_TRUE(fs::exists(dir / "labels.h5"));
  EXPECT_FALSE(fs::exists(dir / "labels.h5.partial"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
}

TEST(LabelsFile, FailedWriteKeepsTheOldFile) {
  ScratchDir dir("labels");
  WriteLabels(dir / "labels.h5", Example());
  LabelSet broken = Example();
  broken.labels[1].pop_back();
  EXPECT_THROW(WriteLabels(dir / "labels.h5", broken), std::invalid_argument);
  EXPECT_TRUE(SameLabels(ReadLabels(dir / "labels.h5"), Example()));
  EXPECT_FALSE(fs::exists(dir / "labels.h5.partial"));

  EXPECT_THROW(WriteLabels(dir / "no_such_dir/labels.h5", Example()), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir / "no_such_dir"));
}

TEST(LabelsFile, RefusesCameraNamesThatCannotNameAGroup) {
  ScratchDir dir("labels");
  for (const char* name : {"", "a/b", "cam_left"}) {
    LabelSet set = Example();
    set.cameras[0] = name;  // "cam_left" makes the names repeat
    EXPECT_THROW(WriteLabels(dir / "labels.h5", set), std::invalid_argument) << name;
  }
  EXPECT_FALSE(fs::exists(dir / "labels.h5"));
}

TEST(LabelsFile, HasTheDocumentedLayoutWithUnitsOnEveryDataset) {
  ScratchDir dir("labels");
  WriteLabels(dir / "labels.h5", Example());
  std::lock_guard<std::mutex> lock(h5::Mutex());
  h5::Id file = h5::OpenFileReadOnly(dir / "labels.h5");
  const hid_t f = file.get();
  EXPECT_EQ(h5::ReadStringAttribute(f, "format"), "netlab-labels");
  EXPECT_EQ(h5::ReadStringAttribute(f, "version"), "1");
  EXPECT_EQ(h5::ReadStringAttribute(f, "cameras"), "cam_right\ncam_left");
  for (const auto& [name, expected] : {std::pair("rows", kRows), std::pair("cols", kCols)}) {
    h5::Id attr(H5Aopen(f, name, H5P_DEFAULT));
    h5::Id type(H5Aget_type(attr.get()));
    EXPECT_EQ(H5Tget_class(type.get()), H5T_INTEGER) << name;
    int value = 0;
    H5Aread(attr.get(), H5T_NATIVE_INT, &value);
    EXPECT_EQ(value, expected) << name;
  }
  const hsize_t t = kFrames, k = kRows * kCols;
  const std::vector<std::pair<std::string, std::vector<hsize_t>>> datasets = {
      {"/frame_index", {t}},
      {"/knots/grid", {k, 2}},
      {"/cameras/cam_left/position_px", {t, k, 2}},
      {"/cameras/cam_left/source", {t, k}},
      {"/cameras/cam_left/confidence", {t, k}},
      {"/cameras/cam_left/state", {t, k}},
      {"/cameras/cam_right/position_px", {t, k, 2}},
  };
  for (const auto& [name, dims] : datasets) {
    EXPECT_EQ(h5::DatasetDims(f, name), dims) << name;
    h5::Id dataset(H5Dopen2(f, name.c_str(), H5P_DEFAULT));
    EXPECT_NE(h5::ReadStringAttribute(dataset.get(), "units"), "") << name;
  }
  std::vector<int> grid(2 * k);
  h5::ReadDataset(f, "/knots/grid", H5T_NATIVE_INT, grid.data());
  EXPECT_EQ(grid[2 * 6], 1);  // knot 6 of a 4-column net is (1, 2)
  EXPECT_EQ(grid[2 * 6 + 1], 2);
}

TEST(LabelsFile, TextFileIsNotHdf5) {
  ScratchDir dir("labels");
  WriteBytes(dir / "labels.h5", "rows: 3\n");
  EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabels(dir / "labels.h5"); }),
                       {dir / "labels.h5", "not an HDF5 file"}));
  EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabels(dir / "absent.h5"); }), {"absent.h5"}));
}

TEST(LabelsFile, WrongFormatAttributeIsNamed) {
  ScratchDir dir("labels");
  const std::string path = dir / "labels.h5";
  WriteLabels(path, Example());
  EditFile(path, [](hid_t f) { h5::WriteStringAttribute(f, "format", "netlab-knot-tracks"); });
  EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabels(path); }),
                       {path, "format", "netlab-knot-tracks", "netlab-labels"}));
}

TEST(LabelsFile, DatasetOfTheWrongShapeIsNamedWithTheExpectedShape) {
  ScratchDir dir("labels");
  const std::string path = dir / "labels.h5";
  struct Case {
    std::string dataset;
    hid_t type;
    std::vector<hsize_t> wrong;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"/frame_index", H5T_NATIVE_INT, {5, 1}, "[T]"},
      {"/knots/grid", H5T_NATIVE_INT, {12, 3}, "[12,2]"},
      {"/cameras/cam_left/position_px", H5T_NATIVE_DOUBLE, {5, 12}, "[5,12,2]"},
      {"/cameras/cam_left/source", H5T_NATIVE_UINT8, {4, 12}, "[5,12]"},
      {"/cameras/cam_right/confidence", H5T_NATIVE_FLOAT, {5, 13}, "[5,12]"},
      {"/cameras/cam_right/state", H5T_NATIVE_UINT8, {5, 12, 1}, "[5,12]"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.dataset);
    WriteLabels(path, Example());
    EditFile(path, [&](hid_t f) { ReplaceDataset(f, c.dataset, c.type, c.wrong); });
    EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabels(path); }), {path, c.dataset, c.expected}));
  }
}

TEST(LabelsFile, MissingDatasetIsNamed) {
  ScratchDir dir("labels");
  const std::string path = dir / "labels.h5";
  WriteLabels(path, Example());
  EditFile(path,
           [](hid_t f) { EXPECT_GE(H5Ldelete(f, "/cameras/cam_right/state", H5P_DEFAULT), 0); });
  EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabels(path); }),
                       {"missing dataset /cameras/cam_right/state", "[5,12]"}));
}

TEST(LabelsFile, NetShapeMustMatchTheGrid) {
  ScratchDir dir("labels");
  const std::string path = dir / "labels.h5";
  WriteLabels(path, Example());
  EditFile(path, [](hid_t f) {
    EXPECT_GE(H5Adelete(f, "rows"), 0);
    const int rows = 4;
    h5::Id space(H5Screate(H5S_SCALAR));
    h5::Id attr(H5Acreate2(f, "rows", H5T_NATIVE_INT, space.get(), H5P_DEFAULT, H5P_DEFAULT));
    H5Awrite(attr.get(), H5T_NATIVE_INT, &rows);
  });
  EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabels(path); }), {"/knots/grid", "[16,2]"}));

  EditFile(path, [](hid_t f) { EXPECT_GE(H5Adelete(f, "cols"), 0); });
  EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabels(path); }), {"cols"}));
}

TEST(LabelsFile, OutOfRangeValuesAreNamed) {
  ScratchDir dir("labels");
  const std::string path = dir / "labels.h5";
  // Row 2, knot 7: flat index 2 * 12 + 7.
  WriteLabels(path, Example());
  // 9: one past the last source (kProjected).
  EditFile(path, [](hid_t f) { SetByte(f, "/cameras/cam_left/source", 31, 9); });
  EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabels(path); }),
                       {"/cameras/cam_left/source", "9", "row 2, knot 7", "LabelSource"}));

  WriteLabels(path, Example());
  EditFile(path, [](hid_t f) { SetByte(f, "/cameras/cam_right/state", 31, 4); });
  EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabels(path); }),
                       {"/cameras/cam_right/state", "4", "row 2, knot 7", "LabelState"}));

  WriteLabels(path, Example());
  EditFile(path, [](hid_t f) {
    ReplaceDataset(f, "/cameras/cam_left/confidence", H5T_NATIVE_FLOAT, {5, 12}, 1.5);
  });
  EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabels(path); }),
                       {"/cameras/cam_left/confidence", "1.5", "outside 0..1"}));
}

TEST(LabelsFile, CamerasAttributeMustMatchTheGroups) {
  ScratchDir dir("labels");
  const std::string path = dir / "labels.h5";
  WriteLabels(path, Example());
  EditFile(path, [](hid_t f) { h5::WriteStringAttribute(f, "cameras", "cam_left"); });
  EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabels(path); }), {"/cameras/cam_right", "not listed"}));

  EditFile(path,
           [](hid_t f) { h5::WriteStringAttribute(f, "cameras", "cam_right\ncam_left\ncam_top"); });
  EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabels(path); }), {"cam_top", "no group"}));

  EditFile(path, [](hid_t f) {
    h5::WriteStringAttribute(f, "cameras", "cam_right\ncam_left\ncam_left");
  });
  EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabels(path); }), {"cameras", "twice"}));
}

// ---------------------------------------------------------------------------------------------
// xypts.csv

// What reading an xypts file gives for `set`: the positions, with every present label imported.
LabelSet AsImported(LabelSet set) {
  for (std::vector<Label>& camera : set.labels)
    for (Label& label : camera)
      label = label.present() ? Label{label.px, LabelSource::kImported, 1.0f, LabelState::kAccepted}
                              : Label{};
  return set;
}

TEST(XyPts, RoundTripIsExact) {
  ScratchDir dir("labels");
  const LabelSet written = Example({0, 1, 2, 3, 4});
  WriteXyPts(dir / "xypts.csv", written);
  EXPECT_FALSE(fs::exists(dir / "xypts.csv.partial"));
  const LabelSet read = ReadXyPts(dir / "xypts.csv", kRows, kCols, written.cameras);
  EXPECT_TRUE(SameLabels(read, AsImported(written)));
  EXPECT_EQ(read.CountPresent(), written.CountPresent());
}

TEST(XyPts, HasTheDltdv8Layout) {
  ScratchDir dir("labels");
  LabelSet set = LabelSet::Empty(1, 2, {"a", "b"}, {0, 1});
  set.at(1, 0, 1).px = Eigen::Vector2d(0.1, -2.5);
  set.at(0, 1, 0).px = Eigen::Vector2d(1e-7, 12345.678);
  set.at(0, 1, 1).px = Eigen::Vector2d(3.0, std::nan(""));  // not present: written as NaN
  WriteXyPts(dir / "xypts.csv", set);
  EXPECT_EQ(ReadText(dir / "xypts.csv"),
            "pt1_cam1_X,pt1_cam1_Y,pt1_cam2_X,pt1_cam2_Y,pt2_cam1_X,pt2_cam1_Y,pt2_cam2_X,"
            "pt2_cam2_Y\n"
            "NaN,NaN,NaN,NaN,NaN,NaN,0.10000000000000001,-2.5\n"
            "9.9999999999999995e-08,12345.678,NaN,NaN,NaN,NaN,NaN,NaN\n");
}

// xypts.csv has no hidden marks: a hidden knot is written as NaN, like an absent one.
TEST(XyPts, AHiddenMarkIsWrittenAsAbsent) {
  ScratchDir dir("labels");
  LabelSet set = LabelSet::Empty(1, 2, {"a"}, {0});
  set.at(0, 0, 0) = Label::Hidden();
  set.at(0, 0, 1).px = Eigen::Vector2d(1.5, 2.0);
  WriteXyPts(dir / "xypts.csv", set);
  EXPECT_EQ(ReadText(dir / "xypts.csv"),
            "pt1_cam1_X,pt1_cam1_Y,pt2_cam1_X,pt2_cam1_Y\nNaN,NaN,1.5,2\n");
}

TEST(XyPts, RowIIsFrameI) {
  ScratchDir dir("labels");
  LabelSet set = LabelSet::Empty(1, 1, {"a"}, {3, 1});
  set.at(0, 0, 0).px = Eigen::Vector2d(30.0, 31.0);
  set.at(0, 1, 0).px = Eigen::Vector2d(10.0, 11.0);
  WriteXyPts(dir / "xypts.csv", set);
  const LabelSet read = ReadXyPts(dir / "xypts.csv", 1, 1, {"a"});
  EXPECT_EQ(read.frame_index, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_FALSE(read.at(0, 0, 0).present());
  EXPECT_EQ(read.at(0, 1, 0).px, Eigen::Vector2d(10.0, 11.0));
  EXPECT_FALSE(read.at(0, 2, 0).present());
  EXPECT_EQ(read.at(0, 3, 0).px, Eigen::Vector2d(30.0, 31.0));

  set.frame_index = {1, 1};
  EXPECT_THROW(WriteXyPts(dir / "twice.csv", set), std::invalid_argument);
  set.frame_index = {-1, 1};
  EXPECT_THROW(WriteXyPts(dir / "negative.csv", set), std::invalid_argument);
}

TEST(XyPts, ColumnsInAnyOrderReadTheSame) {
  ScratchDir dir("labels");
  const LabelSet written = Example({0, 1, 2, 3, 4});
  WriteXyPts(dir / "xypts.csv", written);
  std::vector<std::vector<std::string>> table;
  for (const std::string& line : Split(ReadText(dir / "xypts.csv"), '\n'))
    table.push_back(Split(line, ','));
  std::vector<size_t> order(table[0].size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937(3));
  std::string shuffled;
  for (const std::vector<std::string>& row : table) {
    for (size_t j = 0; j < order.size(); ++j) shuffled += (j ? "," : "") + row[order[j]];
    shuffled += "\n";
  }
  WriteBytes(dir / "shuffled.csv", shuffled);
  ASSERT_NE(shuffled, ReadText(dir / "xypts.csv"));
  EXPECT_TRUE(SameLabels(ReadXyPts(dir / "shuffled.csv", kRows, kCols, written.cameras),
                         ReadXyPts(dir / "xypts.csv", kRows, kCols, written.cameras)));
}

TEST(XyPts, ReadsNanSpellingsEmptyCellsAndWindowsLineEndings) {
  ScratchDir dir("labels");
  WriteBytes(dir / "xypts.csv",
             "pt1_cam1_X,pt1_cam1_Y,pt2_cam1_X,pt2_cam1_Y\r\n"
             "nan,nan,NaN,NaN\r\n"
             ",,1.5,-2\r\n"
             " 7 , 8 ,,\r\n\r\n");
  const LabelSet read = ReadXyPts(dir / "xypts.csv", 1, 2, {"a"});
  ASSERT_EQ(read.frames(), 3);
  EXPECT_EQ(read.CountPresent(), 2);
  const Label& label = read.at(0, 1, 1);
  EXPECT_EQ(label.px, Eigen::Vector2d(1.5, -2.0));
  EXPECT_EQ(label.source, LabelSource::kImported);
  EXPECT_EQ(label.confidence, 1.0f);
  EXPECT_EQ(label.state, LabelState::kAccepted);
  EXPECT_EQ(read.at(0, 2, 0).px, Eigen::Vector2d(7.0, 8.0));
  EXPECT_EQ(read.at(0, 0, 0).source, LabelSource::kNone);
}

// Reads `text` as the xypts file of a 2 x 2 net seen by cameras a and b.
std::string XyPtsError(const std::string& text) {
  ScratchDir dir("labels_bad");
  WriteBytes(dir / "bad.csv", text);
  return ErrorOf([&] { ReadXyPts(dir / "bad.csv", 2, 2, {"a", "b"}); });
}

TEST(XyPts, PointBeyondTheNetIsNamed) {
  EXPECT_TRUE(Mentions(XyPtsError("pt1_cam1_X,pt1_cam1_Y,pt5_cam1_X,pt5_cam1_Y\n1,2,3,4\n"),
                       {"bad.csv:1:", "'pt5_cam1_X'", "point 5", "2 x 2"}));
  EXPECT_TRUE(Mentions(XyPtsError("pt0_cam1_X,pt0_cam1_Y\n1,2\n"), {"'pt0_cam1_X'", "point 0"}));
}

TEST(XyPts, CameraBeyondTheListIsNamed) {
  EXPECT_TRUE(Mentions(XyPtsError("pt1_cam3_Y,pt1_cam3_X\n1,2\n"),
                       {"bad.csv:1:", "'pt1_cam3_Y'", "camera 3"}));
}

TEST(XyPts, UnparsableCellIsNamedByLineAndColumn) {
  EXPECT_TRUE(Mentions(XyPtsError("pt1_cam1_X,pt1_cam1_Y\n1,2\n3,4.5x\n"),
                       {"bad.csv:3:", "'pt1_cam1_Y'", "'4.5x'"}));
  EXPECT_TRUE(Mentions(XyPtsError("pt1_cam1_X,pt1_cam1_Y\ninf,2\n"),
                       {"bad.csv:2:", "'pt1_cam1_X'", "'inf'"}));
}

TEST(XyPts, XWithoutItsYIsAnError) {
  EXPECT_TRUE(Mentions(XyPtsError("pt2_cam1_X,pt2_cam1_Y,pt1_cam2_X\n1,2,3\n"),
                       {"bad.csv:1:", "'pt1_cam2_X'", "pt1_cam2_Y"}));
  EXPECT_TRUE(Mentions(XyPtsError("pt1_cam1_X,pt1_cam1_Y\n1,NaN\n"),
                       {"bad.csv:2:", "pt1_cam1_X", "pt1_cam1_Y", "NaN"}));
}

TEST(XyPts, WrongNumberOfCellsIsNamedByLine) {
  EXPECT_TRUE(Mentions(XyPtsError("pt1_cam1_X,pt1_cam1_Y\n1,2\n3,4\n5\n7,8\n"),
                       {"bad.csv:4:", "expected 2 cells", "got 1"}));
  EXPECT_TRUE(Mentions(XyPtsError("pt1_cam1_X,pt1_cam1_Y\n1,2,\n"), {"bad.csv:2:", "got 3"}));
}

TEST(XyPts, UnknownOrRepeatedColumnsAreNamed) {
  EXPECT_TRUE(Mentions(XyPtsError("frame,pt1_cam1_X,pt1_cam1_Y\n0,1,2\n"), {"'frame'"}));
  EXPECT_TRUE(
      Mentions(XyPtsError("pt1_cam1_X,pt1_cam1_Y,pt1_cam1_X\n1,2,3\n"), {"'pt1_cam1_X'", "twice"}));
  EXPECT_TRUE(Mentions(XyPtsError(""), {"bad.csv", "header"}));
}

// ---------------------------------------------------------------------------------------------
// ReadLabelsAny

TEST(ReadLabelsAny, ChoosesTheReaderByExtension) {
  ScratchDir dir("labels");
  const LabelSet set = Example({0, 1, 2, 3, 4});
  WriteLabels(dir / "labels.h5", set);
  WriteXyPts(dir / "xypts.CSV", set);
  EXPECT_TRUE(SameLabels(ReadLabelsAny(dir / "labels.h5", kRows, kCols, {"x"}), set));
  EXPECT_TRUE(
      SameLabels(ReadLabelsAny(dir / "xypts.CSV", kRows, kCols, set.cameras), AsImported(set)));
}

TEST(ReadLabelsAny, NetShapeOfALabelsFileMustMatch) {
  ScratchDir dir("labels");
  WriteLabels(dir / "labels.h5", Example());
  EXPECT_TRUE(Mentions(ErrorOf([&] { ReadLabelsAny(dir / "labels.h5", 4, 3, {}); }),
                       {"labels.h5", "3 x 4", "4 x 3"}));
}

}  // namespace
}  // namespace netlab::recon
