#include "app/gui/document/calibration_presenter.h"

#include <QFileInfo>
#include <QStringList>
#include <QUndoCommand>
#include <QUndoStack>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <thread>

#include "app/gui/document/project.h"
#include "calibration/detect.h"

namespace netlab::gui {
namespace {

// What the target is, for "not found" reasons.
std::string TargetName(const calib::CalibrationTarget& target) {
  const calib::BoardPattern& p = target.faces[0].pattern;
  if (p.type == calib::PatternType::kChessboard)
    return "chessboard of " + std::to_string(p.cols) + "x" + std::to_string(p.rows) +
           " inner corners";
  if (p.type == calib::PatternType::kCharuco)
    return "ChArUco board of " + std::to_string(p.cols) + "x" + std::to_string(p.rows) +
           " squares (" + p.dictionary + ")";
  return "marker (" + p.dictionary + ")";
}

QString FileName(const std::string& path) {
  return QFileInfo(QString::fromStdString(path)).fileName();
}

}  // namespace

int CoverageGrid::max() const {
  return counts.empty() ? 0 : *std::max_element(counts.begin(), counts.end());
}

// One exclusion or inclusion: the excluded set before and after.
class ExcludeCommand : public QUndoCommand {
 public:
  ExcludeCommand(CalibrationPresenter* presenter, std::set<ImageKey> before,
                 std::set<ImageKey> after, const QString& text)
      : QUndoCommand(text),
        presenter_(presenter),
        before_(std::move(before)),
        after_(std::move(after)) {}
  void redo() override { presenter_->SetExcluded(after_); }
  void undo() override { presenter_->SetExcluded(before_); }

 private:
  CalibrationPresenter* presenter_;
  std::set<ImageKey> before_, after_;
};

CalibrationPresenter::CalibrationPresenter(const calib::Rig* rig, std::string rig_path,
                                           std::string project_path)
    : rig_(rig),
      rig_path_(std::move(rig_path)),
      project_path_(std::move(project_path)),
      undo_(std::make_unique<QUndoStack>()) {}

CalibrationPresenter::~CalibrationPresenter() = default;

// ---- The rig shown.

const calib::Rig& CalibrationPresenter::rig() const {
  static const calib::Rig kNone;
  if (const calib::CalibrationResult* r = result()) return r->rig;
  return rig_ != nullptr ? *rig_ : kNone;
}

std::vector<RigCameraRow> CalibrationPresenter::Cameras() const {
  std::vector<RigCameraRow> rows;
  for (const calib::Camera& c : rig().cameras) {
    const calib::CameraIntrinsics& in = c.intrinsics;
    rows.push_back({c.name, in.width, in.height, in.fx, in.fy, in.cx, in.cy, in.distortion[0],
                    in.distortion[1], c.Center(), c.ViewDirection()});
  }
  return rows;
}

std::vector<Baseline> CalibrationPresenter::Baselines() const {
  const calib::Rig& rig = this->rig();
  std::vector<Baseline> out;
  const int n = static_cast<int>(rig.cameras.size());
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      out.push_back({a, b, (rig.cameras[a].Center() - rig.cameras[b].Center()).norm()});
  std::sort(out.begin(), out.end(),
            [](const Baseline& x, const Baseline& y) { return x.length_m < y.length_m; });
  return out;
}

std::array<Eigen::Vector3d, 5> CalibrationPresenter::Frustum(int c, double depth_m) const {
  const calib::Camera& camera = rig().cameras[c];
  const calib::CameraIntrinsics& in = camera.intrinsics;
  const calib::Rigid3d world_from_cam = camera.cam_from_world.Inverse();
  std::array<Eigen::Vector3d, 5> points;
  points[0] = camera.Center();
  const double us[] = {0, static_cast<double>(in.width), static_cast<double>(in.width), 0};
  const double vs[] = {0, 0, static_cast<double>(in.height), static_cast<double>(in.height)};
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d p_in_cam((us[i] - in.cx) / in.fx * depth_m,
                                   (vs[i] - in.cy) / in.fy * depth_m, depth_m);
    points[i + 1] = world_from_cam * p_in_cam;
  }
  return points;
}

QString CalibrationPresenter::Summary() const {
  const calib::Rig& rig = this->rig();
  QStringList baselines;
  for (const Baseline& b : Baselines())
    baselines << QString("%1–%2 %3 m")
                     .arg(QString::fromStdString(rig.cameras[b.a].name),
                          QString::fromStdString(rig.cameras[b.b].name))
                     .arg(b.length_m, 0, 'f', 3);
  QString source = QString::fromStdString(rig_path_);
  if (result() != nullptr && !saved_) source = "calibrated here (not saved)";
  if (rig.cameras.empty()) return source + ": no cameras";
  return QString("%1: %2 cameras · baselines %3")
      .arg(source)
      .arg(rig.cameras.size())
      .arg(baselines.join(", "));
}

// ---- The inputs.

void CalibrationPresenter::ResetDetections() {
  images_.clear();
  for (int c = 0; c < static_cast<int>(files_.size()); ++c)
    for (int f = 0; f < static_cast<int>(files_[c].size()); ++f) {
      CalibrationImage image;
      image.camera = c;
      image.frame = f;
      image.path = files_[c][f];
      images_.push_back(std::move(image));
    }
  detection_wall_s_ = 0.0;
  detection_cancelled_ = false;
  calibrate_asked_ = false;
  saved_ = false;
  excluded_.clear();
  runs_.clear();
  undo_->clear();
}

void CalibrationPresenter::SetTarget(const std::string& spec) {
  calib::CalibrationTarget target = calib::CalibrationTarget::Parse(spec);
  target_spec_ = spec;
  target_ = std::move(target);
  ResetDetections();
}

void CalibrationPresenter::SetImages(
    const std::vector<std::pair<std::string, std::string>>& globs) {
  std::vector<std::vector<std::string>> files;
  std::vector<std::string> names;
  for (const auto& [name, pattern] : globs) {
    if (name.empty()) throw std::runtime_error("images '" + pattern + "': the camera has no name");
    if (std::find(names.begin(), names.end(), name) != names.end())
      throw std::runtime_error("camera '" + name + "' given twice");
    std::vector<std::string> matched = calib::ImagesMatching(pattern);
    if (matched.empty())
      throw std::runtime_error("images of " + name + ": the pattern '" + pattern +
                               "' matches no file");
    names.push_back(name);
    files.push_back(std::move(matched));
  }
  for (size_t c = 1; c < files.size(); ++c)
    if (files[c].size() != files[0].size())
      throw std::runtime_error("unequal numbers of images per camera: " + names[0] + " has " +
                               std::to_string(files[0].size()) + ", " + names[c] + " has " +
                               std::to_string(files[c].size()) +
                               " (images are matched by their sorted order)");
  globs_ = globs;
  files_ = std::move(files);
  ResetDetections();
}

std::vector<std::pair<std::string, std::string>> CalibrationPresenter::GlobsInFolder(
    const std::string& folder, std::string* target) {
  namespace fs = std::filesystem;
  std::vector<std::pair<std::string, std::string>> globs;
  if (target != nullptr) target->clear();
  std::error_code error;
  if (!fs::is_directory(folder, error)) return globs;
  std::vector<fs::path> entries;
  for (const fs::directory_entry& e : fs::directory_iterator(folder, error))
    entries.push_back(e.path());
  std::sort(entries.begin(), entries.end());
  for (const fs::path& p : entries) {
    if (fs::is_regular_file(p, error) && (p.extension() == ".yaml" || p.extension() == ".yml") &&
        target != nullptr && target->empty()) {
      try {
        calib::CalibrationTarget::Parse(p.string());
        *target = p.string();
      } catch (const std::exception&) {
      }
      continue;
    }
    if (!fs::is_directory(p, error)) continue;
    std::map<std::string, int> by_extension;
    for (const fs::directory_entry& e : fs::directory_iterator(p, error)) {
      std::string ext = e.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
      if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tif" || ext == ".tiff")
        ++by_extension[e.path().extension().string()];
    }
    if (by_extension.empty()) continue;
    const auto most =
        std::max_element(by_extension.begin(), by_extension.end(),
                         [](const auto& a, const auto& b) { return a.second < b.second; });
    globs.emplace_back(p.filename().string(), (p / ("*" + most->first)).string());
  }
  return globs;
}

std::string CalibrationPresenter::SuggestedImagesFolder() const {
  if (project_path_.empty()) return "";
  try {
    const std::filesystem::path folder =
        std::filesystem::path(LoadProject(project_path_).experiment).parent_path() / "calibration";
    std::error_code error;
    if (std::filesystem::is_directory(folder, error)) return folder.string();
  } catch (const std::exception&) {
  }
  return "";
}

int CalibrationPresenter::frames() const {
  return files_.empty() ? 0 : static_cast<int>(files_[0].size());
}

// ---- Detection.

DetectionJob CalibrationPresenter::MakeDetectionJob() const {
  if (!target_) throw std::logic_error("no calibration target chosen");
  if (files_.empty()) throw std::logic_error("no calibration images chosen");
  DetectionJob job;
  job.target = *target_;
  job.images = images_;
  for (CalibrationImage& image : job.images) {
    image.status = CalibrationImage::Status::kNotDetected;
    image.found = {};
    image.why.clear();
  }
  return job;
}

DetectionAnswer CalibrationPresenter::Detect(const DetectionJob& job,
                                             const ProgressReporter& progress) {
  const auto start = std::chrono::steady_clock::now();
  DetectionAnswer answer;
  answer.images = job.images;
  const calib::BoardPattern& pattern = job.target.faces[0].pattern;
  const std::string what = TargetName(job.target);
  const int total = static_cast<int>(answer.images.size());
  std::atomic<int> next{0}, done{0};
  std::mutex mutex;
  auto worker = [&] {
    while (!progress.cancelled()) {
      const int task = next++;
      if (task >= total) return;
      CalibrationImage& image = answer.images[task];
      const cv::Mat read = cv::imread(image.path, cv::IMREAD_UNCHANGED);
      if (read.empty()) {
        image.status = CalibrationImage::Status::kFailed;
        image.why = "unreadable or not an image";
      } else {
        image.width = read.cols;
        image.height = read.rows;
        image.found = calib::DetectPattern(calib::ToGray8(read), pattern);
        image.status = image.found.empty() ? CalibrationImage::Status::kFailed
                                           : CalibrationImage::Status::kFound;
        if (image.found.empty()) image.why = "no " + what + " found";
      }
      const int d = ++done;
      if (progress.reports()) {
        std::lock_guard<std::mutex> lock(mutex);
        progress.Report("images searched", d, total);
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, job.threads); ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  answer.cancelled = done < total;
  // A camera's images share its first image's size (as `netlab calibrate` requires).
  std::map<int, std::pair<int, int>> first_size;
  std::map<int, std::string> first_path;
  for (CalibrationImage& image : answer.images) {
    if (image.width == 0) continue;
    const auto [it, inserted] =
        first_size.emplace(image.camera, std::pair(image.width, image.height));
    if (inserted) {
      first_path[image.camera] = image.path;
      continue;
    }
    if (it->second != std::pair(image.width, image.height)) {
      image.status = CalibrationImage::Status::kFailed;
      image.found = {};
      image.why = std::to_string(image.width) + "x" + std::to_string(image.height) + ", but " +
                  FileName(first_path[image.camera]).toStdString() + " is " +
                  std::to_string(it->second.first) + "x" + std::to_string(it->second.second);
    }
  }
  answer.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return answer;
}

void CalibrationPresenter::SetDetections(DetectionAnswer answer) {
  if (answer.images.size() != images_.size()) return;  // for other images (stale)
  for (size_t i = 0; i < images_.size(); ++i)
    if (answer.images[i].path != images_[i].path) return;
  ResetDetections();
  images_ = std::move(answer.images);
  detection_wall_s_ = answer.wall_s;
  detection_cancelled_ = answer.cancelled;
}

const CalibrationImage& CalibrationPresenter::image(ImageKey key) const {
  return images_.at(static_cast<size_t>(key.first) * frames() + key.second);
}

bool CalibrationPresenter::detected() const {
  if (images_.empty()) return false;
  for (const CalibrationImage& image : images_)
    if (image.status == CalibrationImage::Status::kNotDetected) return false;
  return true;
}

QString CalibrationPresenter::DetectionSummary() const {
  int found = 0, failed = 0, searched = 0;
  for (const CalibrationImage& image : images_) {
    found += image.status == CalibrationImage::Status::kFound;
    failed += image.status == CalibrationImage::Status::kFailed;
  }
  searched = found + failed;
  if (images_.empty()) return "No images chosen.";
  if (searched == 0)
    return QString("%1 images of %2 cameras, not searched yet.").arg(images_.size()).arg(cameras());
  QString text = QString("%1 of %2 images searched%3: the target found in %4, %5 failed · %6 s")
                     .arg(searched)
                     .arg(images_.size())
                     .arg(detection_cancelled_ ? " (cancelled)" : "")
                     .arg(found)
                     .arg(failed)
                     .arg(detection_wall_s_, 0, 'f', 1);
  return text;
}

// ---- Calibration.

CalibrationJob CalibrationPresenter::MakeCalibrationJob() const {
  if (!target_ || !detected()) throw std::logic_error("detect the target in every image first");
  CalibrationJob job;
  job.target = *target_;
  job.excluded = excluded_;
  calib::CalibrationInput& input = job.input;
  const int n = cameras(), num_frames = frames();
  input.num_frames = num_frames;
  input.image_names = files_;
  for (int c = 0; c < n; ++c) {
    input.camera_names.push_back(globs_[c].first);
    // The camera's first image's size (DetectInImages's); a failed first image: the first read.
    cv::Size size;
    for (int f = 0; f < num_frames && size.width == 0; ++f)
      if (image({c, f}).width > 0) size = cv::Size(image({c, f}).width, image({c, f}).height);
    input.image_sizes.push_back(size);
    for (int f = 0; f < num_frames; ++f) {
      const CalibrationImage& i = image({c, f});
      if (i.status != CalibrationImage::Status::kFound || is_excluded({c, f})) continue;
      input.observations.push_back(calib::MakeObservation(c, f, i.found));
    }
  }
  return job;
}

CalibrationRun CalibrationPresenter::Calibrate(const CalibrationJob& job) {
  const auto start = std::chrono::steady_clock::now();
  CalibrationRun run;
  run.excluded = job.excluded;
  try {
    run.result = calib::CalibrateRig(job.target, job.input, job.options);
  } catch (const std::exception& e) {
    run.error = e.what();
  }
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (run.result) run.result->summary.wall_s = run.wall_s;
  return run;
}

void CalibrationPresenter::SetCalibration(CalibrationRun run) {
  calibrate_asked_ = true;
  saved_ = false;
  std::set<ImageKey> key = run.excluded;
  runs_[key] = std::move(run);
}

const CalibrationRun* CalibrationPresenter::run() const {
  const auto it = runs_.find(excluded_);
  return it == runs_.end() ? nullptr : &it->second;
}

const calib::CalibrationResult* CalibrationPresenter::result() const {
  const CalibrationRun* r = run();
  return r != nullptr && r->result ? &*r->result : nullptr;
}

bool CalibrationPresenter::NeedsCalibration() const { return calibrate_asked_ && run() == nullptr; }

QString CalibrationPresenter::CalibrationText() const {
  const CalibrationRun* r = run();
  if (r == nullptr) return calibrate_asked_ ? "Calibrating…" : "Not calibrated yet.";
  if (!r->result) return "The calibration failed: " + QString::fromStdString(r->error);
  const calib::CalibrationSummary& s = r->result->summary;
  QStringList lines;
  lines << QString("RMS %1 px over %2 points (%3 dropped as outliers), %4 left out · %5 s")
               .arg(s.rms_px, 0, 'f', 3)
               .arg(s.observations)
               .arg(s.outliers)
               .arg(r->excluded.size() == 1 ? QString("1 image")
                                            : QString("%1 images").arg(r->excluded.size()))
               .arg(r->wall_s, 0, 'f', 1);
  QStringList baselines, metric;
  for (const calib::PairCheck& p : s.pairs) {
    baselines << QString("%1–%2 %3 m")
                     .arg(QString::fromStdString(p.a), QString::fromStdString(p.b))
                     .arg(p.baseline_m, 0, 'f', 4);
    if (p.segments > 0)
      metric << QString("%1–%2 %3 mm (rms %4 mm, %5 segments)")
                    .arg(QString::fromStdString(p.a), QString::fromStdString(p.b))
                    .arg(p.mean_length_mm, 0, 'f', 3)
                    .arg(p.rms_error_mm, 0, 'f', 3)
                    .arg(p.segments);
  }
  lines << "Baselines: " + baselines.join(", ");
  double nominal = 0.0;
  for (const calib::PairCheck& p : s.pairs)
    if (p.segments > 0) nominal = p.nominal_length_mm;
  lines << (metric.isEmpty()
                ? QString("Metric check: no pair of cameras sees the same points")
                : QString("Metric check (neighbouring points triangulated by each pair, nominal "
                          "%1 mm): %2")
                      .arg(nominal, 0, 'f', 3)
                      .arg(metric.join(", ")));
  if (s.warnings.empty()) lines << "No warnings.";
  for (const std::string& w : s.warnings) lines << "Warning: " + QString::fromStdString(w);
  return lines.join("\n");
}

std::optional<double> CalibrationPresenter::ImageRms(ImageKey key) const {
  const calib::CalibrationResult* r = result();
  if (r == nullptr || key.first >= static_cast<int>(r->summary.cameras.size())) return {};
  for (const auto& [frame, rms] : r->summary.cameras[key.first].image_rms_px)
    if (frame == key.second) return rms;
  return {};
}

std::optional<ImageKey> CalibrationPresenter::WorstImage() const {
  std::optional<ImageKey> worst;
  double worst_rms = -1.0;
  const calib::CalibrationResult* r = result();
  if (r == nullptr) return worst;
  for (int c = 0; c < static_cast<int>(r->summary.cameras.size()); ++c)
    for (const auto& [frame, rms] : r->summary.cameras[c].image_rms_px)
      if (rms > worst_rms) worst_rms = rms, worst = ImageKey(c, frame);
  return worst;
}

std::vector<PointResidual> CalibrationPresenter::Residuals(ImageKey key) const {
  std::vector<PointResidual> out;
  const calib::CalibrationResult* r = result();
  const auto [c, f] = key;
  if (r == nullptr || !target_ || is_excluded(key) || f >= static_cast<int>(r->frame_seen.size()) ||
      !r->frame_seen[f])
    return out;
  const CalibrationImage& i = image(key);
  if (i.status != CalibrationImage::Status::kFound) return out;
  const std::vector<int>& faces = r->summary.face_of_camera;
  const int face = c < static_cast<int>(faces.size()) ? faces[c] : 0;
  const calib::TargetFace& target_face =
      target_->faces[std::min<size_t>(face, target_->faces.size() - 1)];
  const calib::Rigid3d world_from_face = r->world_from_target[f] * target_face.target_from_face;
  const calib::Camera& camera = r->rig.cameras[c];
  for (size_t k = 0; k < i.found.ids.size(); ++k) {
    const int id = i.found.ids[k];
    if (id < 0 || id >= static_cast<int>(target_face.pattern.points.size())) continue;
    const Eigen::Vector2d predicted =
        camera.ProjectWorld(world_from_face * target_face.pattern.points[id]);
    if (!predicted.allFinite()) continue;
    out.push_back({i.found.pixels[k], i.found.pixels[k] - predicted});
  }
  return out;
}

CoverageGrid CalibrationPresenter::Coverage(int c, int cols, int rows) const {
  CoverageGrid grid;
  grid.cols = cols;
  grid.rows = rows;
  grid.counts.assign(static_cast<size_t>(cols) * rows, 0);
  if (c < 0 || c >= cameras()) return grid;
  int width = 0, height = 0;
  for (int f = 0; f < frames() && width == 0; ++f)
    width = image({c, f}).width, height = image({c, f}).height;
  if (width == 0) return grid;
  for (int f = 0; f < frames(); ++f) {
    const CalibrationImage& i = image({c, f});
    if (i.status != CalibrationImage::Status::kFound || is_excluded({c, f})) continue;
    for (const Eigen::Vector2d& p : i.found.pixels) {
      const int x = std::clamp(static_cast<int>(p.x() / width * cols), 0, cols - 1);
      const int y = std::clamp(static_cast<int>(p.y() / height * rows), 0, rows - 1);
      ++grid.counts[static_cast<size_t>(y) * cols + x];
    }
  }
  return grid;
}

// ---- Excluding images.

void CalibrationPresenter::SetExcluded(std::set<ImageKey> excluded) {
  excluded_ = std::move(excluded);
  saved_ = false;
}

void CalibrationPresenter::ToggleExcluded(ImageKey key) {
  if (key.first < 0 || key.first >= cameras() || key.second < 0 || key.second >= frames()) return;
  std::set<ImageKey> after = excluded_;
  const bool exclude = after.count(key) == 0;
  if (exclude)
    after.insert(key);
  else
    after.erase(key);
  const QString text = QString("%1 %2 of %3")
                           .arg(exclude ? "Exclude" : "Include", FileName(image(key).path),
                                QString::fromStdString(camera_name(key.first)));
  undo_->push(new ExcludeCommand(this, excluded_, std::move(after), text));
}

// ---- Save.

void CalibrationPresenter::SetProjectRig(const calib::Rig* rig, std::string rig_path) {
  rig_ = rig;
  rig_path_ = std::move(rig_path);
}

void CalibrationPresenter::Save(const std::string& path) {
  const calib::CalibrationResult* r = result();
  if (r == nullptr) throw std::logic_error("nothing calibrated to save");
  calib::WriteRig(path, r->rig);
  if (!project_path_.empty()) {
    Project project = LoadProject(project_path_);
    project.rig = std::filesystem::absolute(path).string();
    SaveProject(project, project_path_);
  }
  rig_path_ = path;
  saved_ = true;
}

}  // namespace netlab::gui
