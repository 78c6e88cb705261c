#include "libreconstruct/recording/frame_source.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

#include "common/errors.h"
#include "common/hdf5_util.h"
#include "libreconstruct/recording/frame_store.h"
#include "libreconstruct/recording/sequence.h"
#include "tests/libreconstruct/test_files.h"

namespace netlab::recon {
namespace {

using testing::PgmBytes;
using testing::SameImage;
using testing::ScratchDir;
using testing::WriteBytes;
using testing::WritePgm;
namespace fs = std::filesystem;

constexpr int kWidth = 64, kHeight = 48;

// Frame k: every pixel different and k-dependent, so a wrong frame, a shifted row or (16 bit)
// swapped bytes all show.
cv::Mat Frame(int k, int depth, int channels = 1) {
  cv::Mat m(kHeight, kWidth, CV_MAKETYPE(depth, channels));
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x)
      for (int c = 0; c < channels; ++c) {
        if (depth == CV_8U)
          m.ptr<uint8_t>(y)[x * channels + c] =
              static_cast<uint8_t>(3 * x + 5 * y + 7 * k + 50 * c);
        else
          m.ptr<uint16_t>(y)[x * channels + c] =
              static_cast<uint16_t>((1021 * x + 37 * y + 4099 * k + 9001 * c) % 65536);
      }
  return m;
}

std::string Numbered(const std::string& prefix, int k, const std::string& extension) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%s%04d%s", prefix.c_str(), k, extension.c_str());
  return buffer;
}

void WriteImage(const std::string& path, const cv::Mat& image) {
  fs::create_directories(fs::path(path).parent_path());
  if (fs::path(path).extension() == ".pgm")
    WritePgm(path, image);
  else
    ASSERT_TRUE(cv::imwrite(path, image)) << path;
}

// ---------------------------------------------------------------------------------------------
// Image sequences

struct SequenceCase {
  std::string extension;
  int depth;
  int channels;
};

class ImageSequenceTest : public ::testing::TestWithParam<SequenceCase> {};

TEST_P(ImageSequenceTest, FindsTheNumberedFilesAndReadsThemExactly) {
  const SequenceCase& p = GetParam();
  ScratchDir dir("frame_source");
  const std::vector<int> written = {3, 4, 6, 12};  // gaps at 5 and 7..11
  for (int k : written)
    WriteImage(dir / ("seq/" + Numbered("frame_", k, p.extension)), Frame(k, p.depth, p.channels));
  // Files the pattern must not take: other digit counts, other names, other extensions.
  const cv::Mat decoy = Frame(99, p.depth, p.channels);
  WriteImage(dir / ("seq/frame_05" + p.extension), decoy);
  WriteImage(dir / ("seq/frame_00005" + p.extension), decoy);
  WriteImage(dir / ("seq/other_0005" + p.extension), decoy);
  WriteBytes(dir / ("seq/frame_0005" + p.extension + ".bak"), "x");
  WriteBytes(dir / ("seq/frame_00a5" + p.extension), "x");

  const std::string spec = "seq/frame_%04d" + p.extension;
  const auto source = OpenFrameSource(spec, dir.path().string());
  EXPECT_EQ(source->Describe(), spec);
  EXPECT_EQ(source->indices(), written);
  for (int k : written) {
    SCOPED_TRACE("frame " + std::to_string(k));
    FrameInfo info;
    std::string error;
    ASSERT_TRUE(source->Header(k, &info, &error)) << error;
    EXPECT_EQ(info.width, kWidth);
    EXPECT_EQ(info.height, kHeight);
    EXPECT_EQ(info.depth, p.depth);
    EXPECT_EQ(info.channels, p.channels);
    const cv::Mat frame = source->Read(k, &error);
    EXPECT_TRUE(SameImage(frame, Frame(k, p.depth, p.channels))) << error;
    EXPECT_EQ(source->Where(k), dir / ("seq/" + Numbered("frame_", k, p.extension)));
  }
  // A frame the sequence does not have.
  std::string error;
  EXPECT_TRUE(source->Read(5, &error).empty());
  EXPECT_FALSE(error.empty());
}

INSTANTIATE_TEST_SUITE_P(
    Formats, ImageSequenceTest,
    ::testing::Values(SequenceCase{".pgm", CV_8U, 1}, SequenceCase{".pgm", CV_16U, 1},
                      SequenceCase{".png", CV_8U, 1}, SequenceCase{".png", CV_16U, 1},
                      SequenceCase{".png", CV_8U, 3}, SequenceCase{".tif", CV_8U, 1},
                      SequenceCase{".tif", CV_16U, 1}),
    [](const ::testing::TestParamInfo<SequenceCase>& param_info) {
      return param_info.param.extension.substr(1) + (param_info.param.depth == CV_8U ? "8" : "16") +
             "bit" + std::to_string(param_info.param.channels) + "ch";
    });

TEST(ImageSequence, UnpaddedPatternAndAbsoluteSpec) {
  ScratchDir dir("frame_source");
  for (int k : {0, 7, 10, 123}) {
    char name[32];
    std::snprintf(name, sizeof(name), "f%d.png", k);
    WriteImage(dir / name, Frame(k, CV_8U));
  }
  WriteImage(dir / "f007.png", Frame(1, CV_8U));  // zero-padded: not what %d writes
  // An absolute spec ignores the base folder.
  const auto source = OpenFrameSource(dir / "f%d.png", "/nonexistent");
  EXPECT_EQ(source->indices(), (std::vector<int>{0, 7, 10, 123}));
  std::string error;
  EXPECT_TRUE(SameImage(source->Read(7, &error), Frame(7, CV_8U))) << error;
}

TEST(ImageSequence, HandWrittenPgmMatchesOpenCvsReading) {
  // Guards the test's own PGM writer (and the byte order of 16-bit PGM) against an independent
  // reader.
  ScratchDir dir("frame_source");
  for (int depth : {CV_8U, CV_16U}) {
    const std::string path = dir / "check.pgm";
    WritePgm(path, Frame(2, depth));
    EXPECT_TRUE(SameImage(cv::imread(path, cv::IMREAD_UNCHANGED), Frame(2, depth)));
    std::string error;
    EXPECT_TRUE(SameImage(ReadPgm(path, &error), Frame(2, depth))) << error;
  }
}

// ---------------------------------------------------------------------------------------------
// Broken files

TEST(ReadPgm, TruncatedFileIsEmptyWithAnErrorSayingSo) {
  ScratchDir dir("frame_source");
  for (int depth : {CV_8U, CV_16U}) {
    SCOPED_TRACE(depth == CV_8U ? "8 bit" : "16 bit");
    const std::string bytes = PgmBytes(Frame(1, depth));
    const size_t data = static_cast<size_t>(kWidth) * kHeight * (depth == CV_8U ? 1 : 2);
    const size_t header = bytes.size() - data;
    for (size_t keep : {bytes.size() - 1, header + data / 2, header}) {
      SCOPED_TRACE("kept " + std::to_string(keep) + " of " + std::to_string(bytes.size()));
      const std::string path = dir / "cut_0001.pgm";
      WriteBytes(path, bytes.substr(0, keep));
      std::string error;
      EXPECT_TRUE(ReadPgm(path, &error).empty());
      EXPECT_NE(error.find("truncated"), std::string::npos) << error;
      EXPECT_NE(error.find(std::to_string(keep - header) + " of " + std::to_string(data)),
                std::string::npos)
          << error;
      // The header reader sees it too, without reading the pixels.
      FrameInfo info;
      error.clear();
      EXPECT_FALSE(ReadImageHeader(path, &info, &error));
      EXPECT_NE(error.find("truncated"), std::string::npos) << error;
      // And so does a sequence holding it.
      const auto source = OpenFrameSource(dir / "cut_%04d.pgm", "");
      error.clear();
      EXPECT_FALSE(source->Header(1, &info, &error));
      EXPECT_NE(error.find("truncated"), std::string::npos) << error;
      error.clear();
      EXPECT_TRUE(source->Read(1, &error).empty());
      EXPECT_NE(error.find("truncated"), std::string::npos) << error;
    }
  }
}

TEST(ReadPgm, GarbageMissingAndCorruptHeadersAreErrors) {
  ScratchDir dir("frame_source");
  std::string error;
  EXPECT_TRUE(ReadPgm(dir / "missing.pgm", &error).empty());
  EXPECT_NE(error.find("cannot open"), std::string::npos) << error;

  WriteBytes(dir / "garbage.pgm", "this is not an image at all, only some text");
  error.clear();
  EXPECT_TRUE(ReadPgm(dir / "garbage.pgm", &error).empty());
  EXPECT_NE(error.find("not a binary PGM"), std::string::npos) << error;

  WriteBytes(dir / "empty.pgm", "");
  error.clear();
  EXPECT_TRUE(ReadPgm(dir / "empty.pgm", &error).empty());
  EXPECT_FALSE(error.empty());

  for (const std::string header :
       {"P5\n64 -48\n255\n", "P5\n64\n", "P5\n64 48\n70000\n", "P5\n0 48\n255\n"}) {
    WriteBytes(dir / "bad.pgm", header + std::string(kWidth * kHeight * 2, '\0'));
    error.clear();
    EXPECT_TRUE(ReadPgm(dir / "bad.pgm", &error).empty()) << header;
    EXPECT_NE(error.find("corrupt PGM header"), std::string::npos) << header << ": " << error;
  }
}

TEST(ImageSequence, TruncatedAndGarbagePngAreUnreadable) {
  ScratchDir dir("frame_source");
  ASSERT_TRUE(cv::imwrite(dir / "frame_0001.png", Frame(1, CV_8U)));
  const auto size = fs::file_size(dir / "frame_0001.png");
  fs::resize_file(dir / "frame_0001.png", size / 2);
  WriteBytes(dir / "frame_0002.png", "garbage, not a PNG");
  const auto source = OpenFrameSource("frame_%04d.png", dir.path().string());
  EXPECT_EQ(source->indices(), (std::vector<int>{1, 2}));
  std::string error;
  EXPECT_TRUE(source->Read(1, &error).empty());
  EXPECT_FALSE(error.empty());
  error.clear();
  FrameInfo info;
  EXPECT_FALSE(source->Header(2, &info, &error));
  EXPECT_FALSE(error.empty());
  error.clear();
  EXPECT_TRUE(source->Read(2, &error).empty());
  EXPECT_FALSE(error.empty());
}

// The message of the InputError `f` throws, or "" when it throws none.
template <typename F>
std::string InputErrorOf(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(OpenFrameSource, ThrowsInputErrorNamingTheSpec) {
  ScratchDir dir("frame_source");
  WriteImage(dir / "seq/frame_0001.pgm", Frame(1, CV_8U));
  const std::string base = dir.path().string();
  const auto message = [&](const std::string& spec) {
    return InputErrorOf([&] { OpenFrameSource(spec, base); });
  };

  std::string m = message("seq/img_%04d.pgm");
  EXPECT_NE(m.find("seq/img_%04d.pgm"), std::string::npos) << m;
  EXPECT_NE(m.find("matches no file"), std::string::npos) << m;

  m = message("nowhere/frame_%04d.pgm");
  EXPECT_NE(m.find("nowhere/frame_%04d.pgm"), std::string::npos) << m;
  EXPECT_NE(m.find("does not exist"), std::string::npos) << m;

  m = message("seq/frame_%04d_%d.pgm");
  EXPECT_NE(m.find("seq/frame_%04d_%d.pgm"), std::string::npos) << m;

  m = message("seq/frame_%s.pgm");
  EXPECT_NE(m.find("seq/frame_%s.pgm"), std::string::npos) << m;

  // A '%' only in a folder name is not a frame pattern either (and must not escape as another
  // exception type).
  m = message("run_100%/frame.pgm");
  EXPECT_NE(m.find("run_100%/frame.pgm"), std::string::npos) << m;

  m = message("cam0.avi");
  EXPECT_NE(m.find("cam0.avi"), std::string::npos) << m;
  EXPECT_NE(m.find("not found"), std::string::npos) << m;

  WriteBytes(dir / "not_a_video.avi", "garbage");
  m = message("not_a_video.avi");
  EXPECT_NE(m.find("not_a_video.avi"), std::string::npos) << m;

  m = message("store.h5:/cam0");
  EXPECT_NE(m.find("store.h5:/cam0"), std::string::npos) << m;

  WriteBytes(dir / "fake.h5", "not hdf5");
  m = message("fake.h5:/cam0");
  EXPECT_NE(m.find("fake.h5:/cam0"), std::string::npos) << m;
}

// ---------------------------------------------------------------------------------------------
// Video

TEST(VideoSource, ReadsTheFramesOfAnMjpegAviInAnyOrder) {
  ScratchDir dir("frame_source");
  const std::string path = dir / "cam0.avi";
  constexpr int kFrames = 12;
  // Flat, well separated grey levels (plus a colour tint) survive JPEG compression.
  const auto frame = [](int k) {
    return cv::Mat(kHeight, kWidth, CV_8UC3, cv::Scalar(20 + 15 * k, 40 + 10 * k, 200 - 12 * k));
  };
  {
    cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25.0,
                           cv::Size(kWidth, kHeight), true);
    if (!writer.isOpened()) GTEST_SKIP() << "this OpenCV cannot write MJPG .avi files";
    for (int k = 0; k < kFrames; ++k) writer.write(frame(k));
  }
  const auto source = OpenFrameSource("cam0.avi", dir.path().string());
  ASSERT_EQ(source->indices().size(), static_cast<size_t>(kFrames));
  EXPECT_EQ(source->indices().front(), 0);
  EXPECT_EQ(source->indices().back(), kFrames - 1);
  FrameInfo info;
  std::string error;
  ASSERT_TRUE(source->Header(3, &info, &error)) << error;
  EXPECT_EQ(info, (FrameInfo{kWidth, kHeight, CV_8U, 3}));
  EXPECT_FALSE(source->Header(kFrames, &info, &error));
  EXPECT_EQ(source->Where(4), path + "[4]");

  // In order, then jumping back and forth (seeks).
  std::vector<int> order;
  for (int k = 0; k < kFrames; ++k) order.push_back(k);
  for (int k : {9, 2, 3, 11, 0, 6}) order.push_back(k);
  for (int k : order) {
    SCOPED_TRACE("frame " + std::to_string(k));
    const cv::Mat image = source->Read(k, &error);
    ASSERT_FALSE(image.empty()) << error;
    ASSERT_EQ(image.size(), cv::Size(kWidth, kHeight));
    // Lossy: the mean error stays small and the frame is nearer to its own colour than to its
    // neighbours' (a shift by one frame would show).
    const double own = cv::norm(image, frame(k), cv::NORM_L1) / image.total() / 3;
    EXPECT_LT(own, 4.0);
    if (k > 0) {
      EXPECT_LT(own, cv::norm(image, frame(k - 1), cv::NORM_L1) / image.total() / 3);
    }
    if (k + 1 < kFrames) {
      EXPECT_LT(own, cv::norm(image, frame(k + 1), cv::NORM_L1) / image.total() / 3);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// HDF5 frame store

// Three cameras over frames 3..7: cam0 16-bit PGM lacking 5 and 7 (with timestamps), cam1 8-bit
// colour PNG complete, cam2 8-bit PGM whose frame 5 is garbage.
Experiment WriteRecording(const ScratchDir& dir) {
  for (int k : {3, 4, 6}) WriteImage(dir / Numbered("cam0/f", k, ".pgm"), Frame(k, CV_16U));
  for (int k = 3; k <= 7; ++k) WriteImage(dir / Numbered("cam1/f", k, ".png"), Frame(k, CV_8U, 3));
  for (int k = 3; k <= 7; ++k)
    WriteImage(dir / Numbered("cam2/f", k, ".pgm"), Frame(k + 20, CV_8U));
  WriteBytes(dir / "cam2/f0005.pgm", "garbage");
  WriteBytes(dir / "cam0_times.csv", "frame_index,time_s\n3,0.03\n4,0.04\n6,0.06\n");
  Experiment e;
  e.name = "store_test";
  e.fps = 100;
  e.path = dir / "experiment.yaml";
  e.base_dir = dir.path().string();
  CameraSpec cam;
  cam.name = "cam0";
  cam.frames = "cam0/f%04d.pgm";
  cam.bayer = BayerPattern::kRGGB;
  cam.timestamps = dir / "cam0_times.csv";
  e.cameras.push_back(cam);
  cam = CameraSpec{};
  cam.name = "cam1";
  cam.frames = "cam1/f%04d.png";
  e.cameras.push_back(cam);
  cam = CameraSpec{};
  cam.name = "cam2";
  cam.frames = "cam2/f%04d.pgm";
  cam.bayer = BayerPattern::kGBRG;
  cam.bit_depth = 8;
  e.cameras.push_back(cam);
  return e;
}

TEST(FrameStore, RoundTripKeepsPixelsGapsAndFrameIndices) {
  ScratchDir dir("frame_source");
  const SynchronizedSequence sequence(WriteRecording(dir));
  for (int deflate : {0, 4}) {
    SCOPED_TRACE("deflate " + std::to_string(deflate));
    const std::string path = dir / "store.h5";
    int calls = 0, last_done = 0, last_total = 0;
    const Experiment out = ConvertToFrameStore(sequence, path, FrameStoreOptions{deflate},
                                               ProgressReporter([&](const Progress& p) {
                                                 ++calls;
                                                 last_done = static_cast<int>(p.done);
                                                 last_total = static_cast<int>(p.total);
                                               }));
    EXPECT_TRUE(fs::exists(path));
    EXPECT_FALSE(fs::exists(path + ".partial"));
    EXPECT_EQ(last_total, 3 * 5);
    EXPECT_EQ(last_done, 3 * 5);
    EXPECT_EQ(calls, 3 * 5);

    // The experiment that reads the store.
    EXPECT_EQ(out.name, "store_test");
    EXPECT_EQ(out.base_dir, dir.path().string());
    ASSERT_EQ(out.cameras.size(), 3u);
    EXPECT_EQ(out.cameras[0].frames, "store.h5:/cam0");
    EXPECT_EQ(out.cameras[2].frames, "store.h5:/cam2");
    EXPECT_EQ(out.cameras[0].bayer, BayerPattern::kRGGB);
    EXPECT_EQ(out.cameras[0].bit_depth, 16);  // from the files' depth
    EXPECT_EQ(out.cameras[2].bit_depth, 8);
    EXPECT_TRUE(out.cameras[0].timestamps.empty());

    // Every camera through "OUT.h5:/camera": the same indices (gaps stay gaps) and pixels.
    const auto cam0 = OpenFrameSource(dir / "store.h5:/cam0", "");
    EXPECT_EQ(cam0->indices(), (std::vector<int>{3, 4, 6}));
    const auto cam1 = OpenFrameSource("store.h5:/cam1", dir.path().string());
    EXPECT_EQ(cam1->indices(), (std::vector<int>{3, 4, 5, 6, 7}));
    const auto cam2 = OpenFrameSource("store.h5:/cam2", dir.path().string());
    EXPECT_EQ(cam2->indices(), (std::vector<int>{3, 4, 6, 7}));
    std::string error;
    for (int k : cam0->indices()) EXPECT_TRUE(SameImage(cam0->Read(k, &error), Frame(k, CV_16U)));
    for (int k : cam1->indices()) EXPECT_TRUE(SameImage(cam1->Read(k, &error), Frame(k, CV_8U, 3)));
    for (int k : cam2->indices())
      EXPECT_TRUE(SameImage(cam2->Read(k, &error), Frame(k + 20, CV_8U)));
    FrameInfo info;
    ASSERT_TRUE(cam1->Header(7, &info, &error)) << error;
    EXPECT_EQ(info, (FrameInfo{kWidth, kHeight, CV_8U, 3}));
    ASSERT_TRUE(cam0->Header(3, &info, &error)) << error;
    EXPECT_EQ(info, (FrameInfo{kWidth, kHeight, CV_16U, 1}));
    EXPECT_EQ(cam0->Where(6), dir / "store.h5" + std::string(":/cam0[3]"));

    // A gap is no frame, not a black one.
    for (int k : {5, 7, 2, 8}) {
      SCOPED_TRACE("cam0 frame " + std::to_string(k));
      error.clear();
      EXPECT_FALSE(cam0->Header(k, &info, &error));
      error.clear();
      EXPECT_TRUE(cam0->Read(k, &error).empty());
      EXPECT_FALSE(error.empty());
    }
    error.clear();
    EXPECT_TRUE(cam2->Read(5, &error).empty());

    // The timestamps (NaN where unknown) and the attributes.
    {
      std::lock_guard<std::mutex> lock(h5::Mutex());
      const h5::Id file = h5::OpenFileReadOnly(path);
      ASSERT_EQ(h5::DatasetDims(file.get(), "cam0_timestamps"), (std::vector<hsize_t>{5}));
      std::vector<double> times(5);
      h5::ReadDataset(file.get(), "cam0_timestamps", H5T_NATIVE_DOUBLE, times.data());
      EXPECT_DOUBLE_EQ(times[0], 0.03);
      EXPECT_DOUBLE_EQ(times[1], 0.04);
      EXPECT_TRUE(std::isnan(times[2]));
      EXPECT_DOUBLE_EQ(times[3], 0.06);
      EXPECT_TRUE(std::isnan(times[4]));
      std::vector<uint8_t> valid(5);
      h5::ReadDataset(file.get(), "cam2_valid", H5T_NATIVE_UINT8, valid.data());
      EXPECT_EQ(valid, (std::vector<uint8_t>{1, 1, 0, 1, 1}));
      const h5::Id data(H5Dopen2(file.get(), "cam0", H5P_DEFAULT));
      EXPECT_EQ(h5::ReadStringAttribute(data.get(), "bayer"), "RGGB");
      EXPECT_EQ(h5::ReadStringAttribute(data.get(), "bit_depth"), "16");
      EXPECT_EQ(h5::ReadStringAttribute(data.get(), "first_index"), "3");
    }

    // The store as a sequence: the same report of gaps.
    const SynchronizedSequence stored(out);
    EXPECT_EQ(stored.first_frame(), 3);
    EXPECT_EQ(stored.last_frame(), 7);
    const CheckReport report = stored.Check(true, {}, 2);
    EXPECT_EQ(report.cameras[0].missing, (std::vector<int>{5, 7}));
    EXPECT_EQ(report.cameras[2].missing, (std::vector<int>{5}));
    EXPECT_TRUE(report.cameras[1].missing.empty());
    EXPECT_EQ(report.synchronized_frames, 3);  // 3, 4 and 6
  }
}

TEST(FrameStore, AStoreConvertsIntoAnotherStore) {
  // Reading an HDF5 source while writing the new store must not deadlock on the HDF5 lock.
  ScratchDir dir("frame_source");
  const SynchronizedSequence sequence(WriteRecording(dir));
  const Experiment first = ConvertToFrameStore(sequence, dir / "first.h5", {}, {});
  const SynchronizedSequence stored(first);
  const Experiment second = ConvertToFrameStore(stored, dir / "second.h5", {9}, {});
  const auto cam0 = OpenFrameSource("second.h5:/cam0", dir.path().string());
  EXPECT_EQ(cam0->indices(), (std::vector<int>{3, 4, 6}));
  std::string error;
  for (int k : cam0->indices()) EXPECT_TRUE(SameImage(cam0->Read(k, &error), Frame(k, CV_16U)));
}

TEST(FrameStore, MissingDatasetNamesIt) {
  ScratchDir dir("frame_source");
  const SynchronizedSequence sequence(WriteRecording(dir));
  ConvertToFrameStore(sequence, dir / "store.h5", {}, {});
  const std::string m =
      InputErrorOf([&] { OpenFrameSource("store.h5:/cam9", dir.path().string()); });
  EXPECT_NE(m.find("store.h5:/cam9"), std::string::npos) << m;
  EXPECT_NE(m.find("no dataset /cam9"), std::string::npos) << m;
}

}  // namespace
}  // namespace netlab::recon
