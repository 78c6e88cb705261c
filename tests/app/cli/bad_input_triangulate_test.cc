// The bad-input suite of `netlab triangulate` and `netlab score`: each row one kind of
// bad input, the exit status it must end in and what its message must name
// (tests/app/cli/bad_input.h). The fixtures (a rig, labels of a 4 x 4 net seen by its four
// cameras, the net's true tracks) are written at run time, then broken (tests/app/cli/h5_edit.h).

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "calibration/rig.h"
#include "common/hdf5_util.h"
#include "common/tracks/track_file.h"
#include "libreconstruct/labels/label_set.h"
#include "tests/app/cli/bad_input.h"
#include "tests/app/cli/h5_edit.h"

namespace netlab::testing {
namespace {

constexpr int kRows = 4, kCols = 4, kFrames = 12;
constexpr double kFps = 179.0;

Eigen::Vector3d KnotAt(int t, int k, int cols = kCols) {
  return {1.0 + 0.5 * t / kFps, (k % cols - 1.5) * 0.1, (k / cols - 1.5) * 0.1};
}

// The net's tracks over the labels' frames (a `rows` x `cols` net), starting at `t0` s.
KnotTracks Truth(int rows, int cols, double t0 = 0.0) {
  KnotTracks tracks;
  for (int k = 0; k < rows * cols; ++k) tracks.grid.push_back({k / cols, k % cols});
  for (int t = 0; t < kFrames; ++t) {
    tracks.time.push_back(t0 + t / kFps);
    for (int k = 0; k < rows * cols; ++k) {
      tracks.position.push_back(KnotAt(t, k, cols));
      tracks.valid.push_back(1);
    }
  }
  tracks.source = "test";
  return tracks;
}

// Knots lost as a triangulated file loses them: /knots/valid 0 and NaN in their position (and
// covariance), legal content every reader must skip. Knot (0,0) from frame 6 on (a knot-frame
// next to it then has a valid stencil whose error window reaches a lost frame), knot (0,1) in
// frames 0..2 (the net's side is measured along row 0 in the first frame), knot (1,1) in 4..5.
void LoseKnots(KnotTracks* tracks) {
  const int knots = tracks->knots();
  auto lose = [&](int t, int k) {
    const size_t i = static_cast<size_t>(t) * knots + k;
    tracks->valid[i] = 0;
    tracks->position[i] = Eigen::Vector3d::Constant(NAN);
    if (!tracks->covariance.empty()) tracks->covariance[i] = Eigen::Matrix3d::Constant(NAN);
  };
  for (int t = 6; t < tracks->frames(); ++t) lose(t, 0);
  for (int t = 0; t <= 2; ++t) lose(t, 1);
  for (int t = 4; t <= 5; ++t) lose(t, 5);
}

// Rewrites a knot-track file with its time, positions and covariances in other units, scaled to
// match and the "units" attributes saying so.
void ToUnits(const std::string& path, const std::string& time_units, double per_s,
             const std::string& length_units, double per_m) {
  KnotTracks tracks = ReadKnotTracks(path);
  for (double& t : tracks.time) t *= per_s;
  for (Eigen::Vector3d& p : tracks.position) p *= per_m;
  for (Eigen::Matrix3d& c : tracks.covariance) c *= per_m * per_m;
  WriteKnotTracks(path, tracks);
  h5::Id file = h5::OpenFileReadWrite(path);
  h5::SetUnits(file.get(), "time", time_units);
  h5::SetUnits(file.get(), "knots/position", length_units);
  if (!tracks.covariance.empty()) h5::SetUnits(file.get(), "knots/covariance", length_units + "^2");
}

// Gives the datasets `names` (each [T, ...] of `type`s) of the file at `path` an extent of
// `frames` frames, nothing stored: a file of 3 kB that declares 1e11 frames.
void DeclareFrames(const std::string& path, hsize_t frames,
                   const std::vector<std::pair<std::string, hid_t>>& names) {
  h5::Id file = h5::OpenFileReadWrite(path);
  for (const auto& [name, type] : names) {
    std::vector<hsize_t> dims = h5::DatasetDims(file.get(), name);
    H5Ldelete(file.get(), name.c_str(), H5P_DEFAULT);
    const std::vector<hsize_t> frame_dims(dims.begin() + 1, dims.end());
    h5::Id dataset = h5::CreateFrameDataset(file.get(), name, type, frame_dims, 1024);
    dims[0] = frames;
    ASSERT_GE(H5Dset_extent(dataset.get(), dims.data()), 0) << path << ":" << name;
  }
}

class BadInputTriangulate : public CommandTest {
 protected:
  BadInputTriangulate() : CommandTest("bad_input_triangulate") {}
  void SetUp() override {
    CommandTest::SetUp();
    const calib::Rig rig = calib::PaperRig();
    calib::WriteRig(Path("rig.yaml"), rig);
    calib::Rig three = rig;
    three.cameras.pop_back();  // the labels' cam3 is not in it
    calib::WriteRig(Path("rig3.yaml"), three);
    std::filesystem::create_directory(Path("folder.yaml"));
    std::vector<std::string> names;
    for (const auto& c : rig.cameras) names.push_back(c.name);
    std::vector<int> frames;
    for (int t = 0; t < kFrames; ++t) frames.push_back(t);
    recon::LabelSet labels = recon::LabelSet::Empty(kRows, kCols, names, frames);
    recon::WriteLabels(Path("empty.h5"), labels);
    for (int c = 0; c < 4; ++c)
      for (int t = 0; t < kFrames; ++t)
        for (int k = 0; k < kRows * kCols; ++k) {
          recon::Label& l = labels.at(c, t, k);
          l.px = rig.cameras[c].ProjectWorld(KnotAt(t, k));
          l.source = recon::LabelSource::kManual;
          l.confidence = 1.0f;
          l.state = recon::LabelState::kAccepted;
        }
    recon::WriteLabels(Path("labels.h5"), labels);
    for (const char* name : {"repeated.h5", "negative.h5", "inf.h5", "nan.h5"})
      std::filesystem::copy_file(Path("labels.h5"), Path(name));
    PokeH5(Path("repeated.h5"), "/frame_index", 3, 2);
    PokeH5(Path("negative.h5"), "/frame_index", 0, -5);
    PokeH5(Path("inf.h5"), "/cameras/cam0/position_px", 0, INFINITY);
    PokeH5(Path("inf.h5"), "/cameras/cam0/position_px", 1, 1e300);
    for (const std::string& camera : names)
      FillH5(Path("nan.h5"), "/cameras/" + camera + "/position_px", NAN);

    WriteKnotTracks(Path("truth.h5"), Truth(kRows, kCols));
    WriteKnotTracks(Path("truth6.h5"), Truth(6, 6));
    WriteKnotTracks(Path("truth_late.h5"), Truth(kRows, kCols, 100.0));
    for (const char* name : {"backwards.h5", "int.h5"})
      std::filesystem::copy_file(Path("truth.h5"), Path(name));
    PokeH5(Path("backwards.h5"), "/time", 5, -0.05);
    RetypeH5ToInt32(Path("int.h5"), "/knots/position");
    std::ofstream(Path("text.h5")) << "not an HDF5 file\n";
    const NetlabResult measured = RunNetlab(Base() + "--labels " + Path("labels.h5") + " --out " +
                                            Path("measured.h5") + " --quiet");
    ASSERT_EQ(measured.status, 0) << measured.err;

    // Legal files score used to crash on, and files in other units.
    KnotTracks lost = ReadKnotTracks(Path("truth.h5"));
    LoseKnots(&lost);
    WriteKnotTracks(Path("lost.h5"), lost);
    KnotTracks measured_lost = ReadKnotTracks(Path("measured.h5"));
    LoseKnots(&measured_lost);
    WriteKnotTracks(Path("measured_lost.h5"), measured_lost);
    // The truth measured with 1 mm of noise (a fixed pattern), in s and m, and in ms and mm.
    KnotTracks noisy = Truth(kRows, kCols);
    for (size_t i = 0; i < noisy.position.size(); ++i) {
      noisy.position[i] +=
          1e-3 * Eigen::Vector3d(std::sin(1.0 * i), std::cos(2.0 * i), std::sin(3.0 * i + 1));
      noisy.covariance.push_back(Eigen::Matrix3d::Identity() * 1e-6);
    }
    WriteKnotTracks(Path("noisy.h5"), noisy);
    WriteKnotTracks(Path("noisy_mm.h5"), noisy);
    ToUnits(Path("noisy_mm.h5"), "ms", 1e3, "mm", 1e3);
    std::filesystem::copy_file(Path("measured.h5"), Path("measured_furlong.h5"));
    ToUnits(Path("measured_furlong.h5"), "s", 1.0, "furlong", 1.0 / 201.168);
    std::filesystem::create_symlink(Path("truth.h5"), Path("link_to_truth.h5"));
    std::filesystem::create_symlink("/dev/null", Path("link_to_null"));
    ASSERT_EQ(mkfifo(Path("fifo").c_str(), 0644), 0);
    std::ofstream(Path("old_score.h5")) << "the previous score";
    std::ofstream(Path("old_report.html")) << "the previous report";
    std::ofstream(Path("old_xyzpts.csv")) << "the previous points";
    std::ofstream(Path("old_xyzres.csv")) << "the previous residuals";
    // Numbers no measurement has: variances of 1e-300 and 1e300 m^2, a contact time stored as NaN
    // or a billion seconds before the flight, a grid that lists knot (1,0) twice and (1,1) not.
    for (const auto& [name, variance] :
         {std::pair<const char*, double>{"cov_tiny.h5", 1e-300}, {"cov_huge.h5", 1e300}}) {
      KnotTracks tracks = Truth(kRows, kCols);
      tracks.covariance.assign(tracks.position.size(), Eigen::Matrix3d::Identity() * variance);
      WriteKnotTracks(Path(name), tracks);
    }
    std::filesystem::copy_file(Path("truth.h5"), Path("contact_nan.h5"));
    {
      h5::Id file = h5::OpenFileReadWrite(Path("contact_nan.h5"));
      const double nan = NAN;
      h5::WriteDataset(file.get(), "contact_start", H5T_NATIVE_DOUBLE, {1}, &nan);
    }
    KnotTracks early = Truth(kRows, kCols);
    early.contact_start_s = -1e9;
    WriteKnotTracks(Path("contact_early.h5"), early);
    KnotTracks one_frame = Truth(kRows, kCols);
    one_frame.time.resize(1);
    one_frame.position.resize(kRows * kCols);
    one_frame.valid.resize(kRows * kCols);
    WriteKnotTracks(Path("one_frame.h5"), one_frame);
    KnotTracks all_lost = Truth(kRows, kCols);
    all_lost.valid.assign(all_lost.valid.size(), 0);
    all_lost.position.assign(all_lost.position.size(), Eigen::Vector3d::Constant(NAN));
    WriteKnotTracks(Path("all_lost.h5"), all_lost);
    // Files that declare 1e11 frames (3 kB each): a bare "out of memory" named neither.
    std::filesystem::copy_file(Path("truth.h5"), Path("declared_huge.h5"));
    DeclareFrames(Path("declared_huge.h5"), 100000000000ULL,
                  {{"/time", H5T_NATIVE_DOUBLE},
                   {"/knots/position", H5T_NATIVE_DOUBLE},
                   {"/knots/valid", H5T_NATIVE_UINT8}});
    std::filesystem::copy_file(Path("labels.h5"), Path("labels_huge.h5"));
    DeclareFrames(Path("labels_huge.h5"), 100000000000ULL, {{"/frame_index", H5T_NATIVE_INT}});
    KnotTracks twice = Truth(kRows, kCols);
    twice.grid[5] = twice.grid[4];
    WriteKnotTracks(Path("grid_twice.h5"), twice);
  }
  std::string Base() const {
    return "triangulate --rig " + Path("rig.yaml") + " --knots 4x4 --fps 179 ";
  }
};

TEST_F(BadInputTriangulate, EachKindEndsInAClearError) {
  const std::string base = "triangulate --rig {dir}/rig.yaml --knots 4x4 --fps 179 ";
  const std::string good = base + "--labels {dir}/labels.h5 ";
  ExpectBadInputs(
      {
          {"missing labels",
           base + "--labels {dir}/missing.h5 --out {dir}/t.h5",
           1,
           {"{dir}/missing.h5"}},
          {"labels not HDF5",
           base + "--labels {dir}/text.h5 --out {dir}/t.h5",
           1,
           {"{dir}/text.h5"}},
          {"labels of another net",
           "triangulate --rig {dir}/rig.yaml --knots 5x5 --fps 179 "
           "--labels {dir}/labels.h5 --out {dir}/t.h5",
           1,
           {"{dir}/labels.h5", "4", "5"}},
          {"a repeated frame",
           base + "--labels {dir}/repeated.h5 --out {dir}/t.h5",
           1,
           {"{dir}/repeated.h5", "/frame_index[3] = 2 is not after [2] = 2"}},
          {"a negative frame",
           base + "--labels {dir}/negative.h5 --out {dir}/t.h5",
           1,
           {"{dir}/negative.h5", "/frame_index[0] = -5 is negative"}},
          {"a label at infinity",
           base + "--labels {dir}/inf.h5 --out {dir}/t.h5",
           1,
           {"{dir}/inf.h5", "/cameras/cam0/position_px", "row 0, knot 0", "not a position"}},
          {"every label NaN",
           base + "--labels {dir}/nan.h5 --out {dir}/t.h5",
           1,
           {"{dir}/nan.h5", "position_px", "not a position"}},
          {"no label at all",
           base + "--labels {dir}/empty.h5 --out {dir}/t.h5",
           1,
           {"{dir}/empty.h5", "no knot is labeled in two cameras", "12 frames"}},
          {"the truth of another net",
           good + "--out {dir}/t.h5 --truth {dir}/truth6.h5",
           1,
           {"--truth {dir}/truth6.h5", "a 6x6 net", "4x4"}},
          {"the truth of other frames",
           good + "--out {dir}/t.h5 --truth {dir}/truth_late.h5",
           1,
           {"--truth {dir}/truth_late.h5", "no frame in common"}},
          {"a truth whose time runs back",
           good + "--out {dir}/t.h5 --truth {dir}/backwards.h5",
           1,
           {"{dir}/backwards.h5", "/time is not increasing at row 5"}},
          {"a truth stored as integers",
           good + "--out {dir}/t.h5 --truth {dir}/int.h5",
           1,
           {"{dir}/int.h5", "/knots/position is int32, expected floating point"}},
          {"a prior of 0", good + "--out {dir}/t.h5 --smooth-sigma 0", 2, {"--smooth-sigma"}},
          {"a noise of 0", good + "--out {dir}/t.h5 --sigma-px 0", 2, {"--sigma-px"}},
          {"a link length of 0", good + "--out {dir}/t.h5 --link-length 0", 2, {"--link-length"}},
          {"no --fps",
           "triangulate --rig {dir}/rig.yaml --knots 4x4 --labels {dir}/labels.h5 "
           "--out {dir}/t.h5",
           2,
           {"--fps"}},
          {"a bad --knots",
           "triangulate --rig {dir}/rig.yaml --knots 4by4 --fps 179 "
           "--labels {dir}/labels.h5 --out {dir}/t.h5",
           2,
           {"--knots"}},
          {"missing rig",
           "triangulate --rig {dir}/missing.yaml --knots 4x4 --fps 179 "
           "--labels {dir}/labels.h5 --out {dir}/t.h5",
           1,
           {"{dir}/missing.yaml"}},
          {"a folder as the rig",
           "triangulate --rig {dir}/folder.yaml --knots 4x4 --fps 179 "
           "--labels {dir}/labels.h5 --out {dir}/t.h5",
           1,
           {"{dir}/folder.yaml: is a folder, not a rig file"}},
          {"a rig with fewer cameras than the labels",
           "triangulate --rig {dir}/rig3.yaml --knots 4x4 --fps 179 --labels {dir}/labels.h5 "
           "--out {dir}/t.h5",
           1,
           {"{dir}/labels.h5", "cam3", "{dir}/rig3.yaml"}},
          {"labels declaring 1e11 frames",
           base + "--labels {dir}/labels_huge.h5 --out {dir}/t.h5",
           1,
           {"{dir}/labels_huge.h5: /frame_index gives 100000000000 frames of 16 knots in 4 "
            "cameras: reading them needs ~",
            "available"}},
          {"empty --out", good + "--out ''", 2, {"--out needs a non-empty value"}},
          {"--out in a folder that is a file",
           good + "--out {dir}/rig.yaml/t.h5",
           1,
           {"{dir}/rig.yaml/t.h5"}},
          // An output over an input or the other output, or where no file can go.
          {"--out is the --labels file",
           good + "--out {dir}/labels.h5",
           1,
           {"--out {dir}/labels.h5", "the --labels file {dir}/labels.h5"},
           {"{dir}/labels.h5"}},
          {"--out is the --rig file",
           good + "--out {dir}/rig.yaml",
           1,
           {"--out {dir}/rig.yaml", "the --rig file {dir}/rig.yaml"},
           {"{dir}/rig.yaml"}},
          {"--out is the --truth file",
           good + "--out {dir}/truth.h5 --truth {dir}/truth.h5",
           1,
           {"--out {dir}/truth.h5", "the --truth file {dir}/truth.h5"},
           {"{dir}/truth.h5"}},
          {"--csv names --out",
           good + "--out {dir}/t_xyzpts.csv --csv {dir}/t_",
           1,
           {"--csv {dir}/t_xyzpts.csv", "is also --out {dir}/t_xyzpts.csv"}},
          {"--csv in a folder that does not exist",
           good + "--out {dir}/old_score.h5 --csv {dir}/no/such/run_",
           1,
           {"--csv {dir}/no/such/run_xyzpts.csv", "does not exist", "nothing was written"},
           {"{dir}/old_score.h5"}},
          {"--out is a FIFO",
           good + "--out {dir}/fifo",
           1,
           {"--out {dir}/fifo", "a FIFO"},
           {"{dir}/fifo"}},
      },
      dir_.string());
  EXPECT_FALSE(std::filesystem::exists(dir_ / "t.h5"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "t.h5.partial"));
}

TEST_F(BadInputTriangulate, ScoreEndsInAClearError) {
  const std::string base = "score --measured {dir}/measured.h5 ";
  ExpectBadInputs(
      {
          {"missing measurement",
           "score --measured {dir}/missing.h5 --sim {dir}/truth.h5 --out "
           "{dir}/s.h5",
           1,
           {"{dir}/missing.h5"}},
          {"measurement not HDF5",
           "score --measured {dir}/text.h5 --sim {dir}/truth.h5 --out "
           "{dir}/s.h5",
           1,
           {"{dir}/text.h5"}},
          {"a simulation stored as integers",
           base + "--sim {dir}/int.h5 --out {dir}/s.h5",
           1,
           {"{dir}/int.h5", "/knots/position is int32, expected floating point"}},
          {"a simulation whose time runs back",
           base + "--sim {dir}/backwards.h5 --out {dir}/s.h5",
           1,
           {"{dir}/backwards.h5", "/time is not increasing at row 5"}},
          {"an unknown --align",
           base + "--sim {dir}/truth.h5 --out {dir}/s.h5 --align sideways",
           2,
           {"--align"}},
          {"empty --out",
           base + "--sim {dir}/truth.h5 --out ''",
           2,
           {"--out needs a non-empty value"}},
          {"empty --report",
           base + "--sim {dir}/truth.h5 --out {dir}/s.h5 --report ''",
           2,
           {"--report needs a non-empty value"}},
          // An output over an input or the other output, or where no file can go.
          {"--out is the --measured file",
           base + "--sim {dir}/truth.h5 --out {dir}/measured.h5",
           1,
           {"--out {dir}/measured.h5", "the --measured file {dir}/measured.h5"},
           {"{dir}/measured.h5"}},
          {"--out is a link to the --sim file",
           base + "--sim {dir}/truth.h5 --out {dir}/link_to_truth.h5",
           1,
           {"--out {dir}/link_to_truth.h5", "the --sim file {dir}/truth.h5"},
           {"{dir}/truth.h5", "{dir}/link_to_truth.h5"}},
          {"--report is --out",
           base + "--sim {dir}/truth.h5 --out {dir}/s.h5 --report {dir}/s.h5",
           1,
           {"--report {dir}/s.h5", "is also --out {dir}/s.h5"}},
          {"--out is a FIFO",
           base + "--sim {dir}/truth.h5 --out {dir}/fifo",
           1,
           {"--out {dir}/fifo", "a FIFO", "not a regular file"},
           {"{dir}/fifo"}},
          {"--out is a link to a character device",
           base + "--sim {dir}/truth.h5 --out {dir}/link_to_null",
           1,
           {"--out {dir}/link_to_null", "a character device"},
           {"{dir}/link_to_null"}},
          {"--report in a folder that does not exist",
           base + "--sim {dir}/truth.h5 --out {dir}/old_score.h5 --report {dir}/no/such/r.html",
           1,
           {"--report {dir}/no/such/r.html", "does not exist", "nothing was written"},
           {"{dir}/old_score.h5"}},
          {"positions in unknown units",
           "score --measured {dir}/measured_furlong.h5 --sim "
           "{dir}/truth.h5 --out {dir}/s.h5",
           1,
           {"{dir}/measured_furlong.h5:/knots/position has units 'furlong'", "mm"}},
          {"variances of 1e-300 m^2",
           "score --measured {dir}/cov_tiny.h5 --sim {dir}/truth.h5 "
           "--out {dir}/s.h5",
           1,
           {"{dir}/cov_tiny.h5:/knots/covariance: frame 0, knot 0: variance 1e-300 m^2",
            "outside 1e-40..1e6 m^2"}},
          {"variances of 1e300 m^2",
           "score --measured {dir}/measured.h5 --sim {dir}/cov_huge.h5 "
           "--out {dir}/s.h5",
           1,
           {"{dir}/cov_huge.h5:/knots/covariance: frame 0, knot 0: variance 1e+300 m^2"}},
          {"a contact time before the simulation",
           base + "--sim {dir}/truth.h5 --out {dir}/s.h5 "
                  "--contact-time -5",
           1,
           {"--contact-time -5 s is outside the time of the simulation {dir}/truth.h5"}},
          {"a /contact_start of NaN",
           base + "--sim {dir}/contact_nan.h5 --out {dir}/s.h5",
           1,
           {"{dir}/contact_nan.h5:/contact_start is nan, not a time"}},
          {"a /contact_start a billion seconds early",
           base + "--sim {dir}/contact_early.h5 --out {dir}/s.h5",
           1,
           {"{dir}/contact_early.h5:/contact_start -1e+09 s is outside the time of the "
            "simulation"}},
          {"a measurement of one frame",
           "score --measured {dir}/one_frame.h5 --sim "
           "{dir}/truth.h5 --meas-sigma 0.001 --out {dir}/s.h5",
           1,
           {"{dir}/one_frame.h5: 1 frame: a score compares a flight over time"}},
          {"a simulation with every knot lost",
           base + "--sim {dir}/all_lost.h5 --out {dir}/s.h5",
           1,
           {"{dir}/all_lost.h5: no knot is valid in any of its 12 frames"}},
          {"a measurement declaring 1e11 frames",
           "score --measured {dir}/declared_huge.h5 --sim "
           "{dir}/truth.h5 --out {dir}/s.h5",
           1,
           {"{dir}/declared_huge.h5: /time and /knots/grid give 100000000000 frames of 16 knots: "
            "reading them needs ~",
            "available"}},
          {"a grid with a knot twice",
           "score --measured {dir}/grid_twice.h5 --sim "
           "{dir}/truth.h5 --out {dir}/s.h5",
           1,
           {"{dir}/grid_twice.h5:/knots/grid: knots 4 and 5 are both (1, 0)"}},
      },
      dir_.string());
  EXPECT_FALSE(std::filesystem::exists(dir_ / "s.h5"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "old_score.h5.partial"));
}

// A disk that fills while the outputs are written (a file-size limit stands in for it): exit 1
// naming the output, every previous output byte for byte, no partial file beside any.
TEST_F(BadInputTriangulate, AFullDiskLeavesThePreviousOutputs) {
  const std::string good = Base() + "--labels {dir}/labels.h5 --quiet ";
  ExpectBadInputs(
      {
          {"triangulate onto a full disk",
           good + "--out {dir}/old_score.h5",
           1,
           {"{dir}/old_score.h5"},
           {"{dir}/old_score.h5"},
           4096},
          {"triangulate with --csv onto a full disk",
           good + "--out {dir}/old_score.h5 --csv {dir}/old_",
           1,
           {"{dir}/old_"},
           {"{dir}/old_score.h5", "{dir}/old_xyzpts.csv", "{dir}/old_xyzres.csv"},
           4096},
          {"score onto a full disk",
           "score --measured {dir}/measured.h5 --sim {dir}/truth.h5 --out {dir}/old_score.h5 "
           "--report {dir}/old_report.html --quiet",
           1,
           {"{dir}/old_"},
           {"{dir}/old_score.h5", "{dir}/old_report.html"},
           4096},
      },
      dir_.string());
}

// A simulation with knots lost (NaN where /knots/valid is 0), and a triangulated file given as
// --sim, are legal: they segfaulted with --align none and rigid (a NaN interpolation error
// indexed the d2 histogram out of its bins) and found "no overlap in time" with the time fitted.
// The lost knot-frames are masked; the rest is scored.
TEST_F(BadInputTriangulate, ScoreSkipsTheKnotsASimulationLost) {
  for (const char* sim : {"lost.h5", "measured_lost.h5"})
    for (const char* align : {"none", "rigid", "time", "time+rigid"}) {
      SCOPED_TRACE(std::string(sim) + " --align " + align);
      const NetlabResult r =
          RunNetlab("score --measured " + Path("measured.h5") + " --sim " + Path(sim) + " --out " +
                    Path("s.h5") + " --align " + align + " --json --quiet");
      ASSERT_EQ(r.status, 0) << r.err;
      const Json json = LastJson(r.out);
      EXPECT_GT(json["masked"].number(), 0);
      EXPECT_GT(json["points"].number(), kFrames * kRows * kCols / 2);
      EXPECT_TRUE(std::isfinite(json["mean_d2"].number()));
      EXPECT_TRUE(std::isfinite(json["rms_percent_of_side"].number()));
    }
}

// A "units" attribute is honoured: the measurement in ms and mm scores as the one in s and m (it
// was read as metres: a net 1000 times larger).
TEST_F(BadInputTriangulate, ScoreConvertsMillisecondsAndMillimetres) {
  auto score = [&](const std::string& measured) {
    const NetlabResult r =
        RunNetlab("score --measured " + Path(measured) + " --sim " + Path("truth.h5") + " --out " +
                  Path("s.h5") + " --align none --json --quiet");
    EXPECT_EQ(r.status, 0) << r.err;
    return LastJson(r.out);
  };
  const Json si = score("noisy.h5"), mm = score("noisy_mm.h5");
  EXPECT_NEAR(si["mean_d2"].number(), 1.5, 0.3);  // sin^2 + cos^2 + sin^2 mm^2 over 1 mm^2
  for (const char* key : {"rms_mm", "mean_d2", "side_m", "max_area_measured_m2"})
    EXPECT_NEAR(mm[key].number(), si[key].number(), 1e-9 * std::abs(si[key].number())) << key;
  EXPECT_EQ(mm["points"].number(), si["points"].number());
}

}  // namespace
}  // namespace netlab::testing
