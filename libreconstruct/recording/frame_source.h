#pragma once
// Where a camera's frames come from: a numbered image sequence, a video file or an HDF5 frame
// store. A source lists the frame indices it has and reads one frame at a time (the recordings
// are hundreds of GB: nothing is loaded whole). Every source may be read from several threads.
//
// Specs (relative paths resolve against the experiment file's folder):
//   cam0/frame_%06d.pgm     printf pattern (%d, %Nd, %0Nd) of PGM/PNG/TIFF files, 8 or 16 bit
//   cam0.avi                a video file (OpenCV VideoCapture; frame k is the k-th frame)
//   store.h5:/cam0          an HDF5 dataset [T, H, W] (or [T, H, W, 3]) of the frame store

#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace netlab::recon {

struct FrameInfo {
  int width = 0;
  int height = 0;
  int depth = 0;     // CV_8U or CV_16U
  int channels = 0;  // 1 (mono or mosaic) or 3
  bool operator==(const FrameInfo& o) const {
    return width == o.width && height == o.height && depth == o.depth && channels == o.channels;
  }
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual std::string Describe() const = 0;
  // The frame indices present, sorted.
  virtual const std::vector<int>& indices() const = 0;
  // The frame's size and type from its header only (cheap); false with the reason when it cannot
  // be read (missing, truncated, not an image).
  virtual bool Header(int index, FrameInfo* info, std::string* error) const = 0;
  // The raw frame (a Bayer mosaic, mono or colour); empty with the reason when unreadable.
  virtual cv::Mat Read(int index, std::string* error) const = 0;
  // Where frame `index` lives (a file name, or "store.h5:/cam0[12]"), for reports.
  virtual std::string Where(int index) const = 0;
  // Frame times (s) the source itself carries (the frame store does); empty when it has none.
  virtual std::map<int, double> Timestamps() const { return {}; }
};

// Opens a source; throws InputError naming the spec when the file is missing, the pattern matches
// no file or the dataset does not exist.
std::unique_ptr<FrameSource> OpenFrameSource(const std::string& spec, const std::string& base_dir);

// Turns OpenCV's own logging off, once per process: its warnings (GStreamer's failed pipeline,
// a codec's complaint) would otherwise come before netlab's message about the same file, which
// names the file and what was expected. Called by every source that opens files with OpenCV.
void SilenceOpenCvLogging();

// Reads a binary PGM (P5, 8 or 16 bit, big-endian as the format says) faster than cv::imread (a
// 2048 x 2048 16-bit frame in ~2 ms instead of 6), detecting truncated files from the header.
cv::Mat ReadPgm(const std::string& path, std::string* error);
// The header of a PGM or PNG file (other formats: decoded to learn the size); false with the
// reason when the file is empty, unreadable, or its content is not the format its extension
// names ("a PNG file named .pgm": decoding goes by the extension, so the check does too).
bool ReadImageHeader(const std::string& path, FrameInfo* info, std::string* error);

}  // namespace netlab::recon
