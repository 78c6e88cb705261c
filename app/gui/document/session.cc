#include "app/gui/document/session.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <utility>

#include "calibration/camera.h"
#include "common/errors.h"
#include "libreconstruct/coloring/colour_science.h"
#include "libreconstruct/coloring/net_coloring.h"
#include "libreconstruct/labeling/knot_detect.h"
#include "libreconstruct/labeling/label_identity.h"
#include "libreconstruct/labeling/label_setup.h"
#include "libreconstruct/recording/experiment.h"

namespace netlab::gui {
namespace {

// The labels of the project: its file when it exists (the same net and cameras), else empty.
recon::LabelSet OpenLabels(const Project& p, const std::vector<std::string>& cameras,
                           const std::vector<int>& frames) {
  recon::LabelSet empty = recon::LabelSet::Empty(p.rows, p.cols, cameras, frames);
  if (!std::filesystem::exists(p.labels)) {
    // New labels: their folder must be there, or no edit could be journaled nor saved.
    const std::filesystem::path folder = std::filesystem::path(p.labels).parent_path();
    if (!folder.empty() && !std::filesystem::is_directory(folder))
      throw InputError(p.labels + ": the labels' folder " + folder.string() +
                       " does not exist, so they could never be saved (create it, or name "
                       "another labels file in the project)");
    return empty;
  }
  const recon::LabelSet read = recon::ReadLabelsAny(p.labels, p.rows, p.cols, cameras);
  // Onto the recording's frames, by camera name and frame number.
  for (size_t rc = 0; rc < read.cameras.size(); ++rc) {
    const int c = empty.FindCamera(read.cameras[rc]);
    if (c < 0)
      throw InputError(p.labels + ": camera '" + read.cameras[rc] + "' is not in the experiment");
    for (int rt = 0; rt < read.frames(); ++rt) {
      const int t = read.frame_index[rt] - frames.front();
      if (t < 0 || t >= empty.frames())
        throw InputError(p.labels + ": frame " + std::to_string(read.frame_index[rt]) +
                         " is outside the recording's frames " + std::to_string(frames.front()) +
                         ":" + std::to_string(frames.back()));
      for (int k = 0; k < empty.knots(); ++k)
        empty.at(c, t, k) = read.at(static_cast<int>(rc), rt, k);
    }
  }
  // Why labels are under review, moved with them (by camera name and frame number).
  for (const auto& [key, why] : read.reasons) {
    const auto [rc, rt, k] = key;
    const int c = empty.FindCamera(read.cameras[rc]);
    empty.reasons[{c, read.frame_index[rt] - frames.front(), k}] = why;
  }
  return empty;
}

}  // namespace

std::unique_ptr<Session> Session::Open(const Project& project,
                                       recon::FrameCacheOptions cache_options) {
  std::unique_ptr<Session> s(new Session());
  s->project_ = project;
  s->sequence_ =
      std::make_unique<recon::SynchronizedSequence>(recon::LoadExperiment(project.experiment));
  s->rig_ = calib::ReadRig(project.rig);
  for (const auto& c : s->sequence_->experiment().cameras) {
    const int r = s->rig_.Find(c.name);
    if (r < 0)
      throw InputError(project.rig + ": no camera '" + c.name +
                       "' (the experiment's cameras must be in the rig)");
    s->camera_names_.push_back(c.name);
    s->rig_index_.push_back(r);
  }
  if (s->sequence_->last_frame() < s->sequence_->first_frame())
    throw InputError(project.experiment + ": the recording has no frames");
  for (int f = s->sequence_->first_frame(); f <= s->sequence_->last_frame(); ++f)
    s->frame_numbers_.push_back(f);
  // The engine set up as netlab label sets it up, with the colour check when the project has
  // the net's colouring.
  recon::LabelingNet net;
  net.link_length_m = project.mesh_m;
  net.knotless = project.knotless;
  std::optional<recon::NetColoring> coloring;
  if (!project.coloring.empty()) {
    coloring = recon::ReadColoring(project.coloring, &net.dyes);
    if (coloring->rows != project.rows || coloring->cols != project.cols)
      throw InputError(project.coloring + ": a " + std::to_string(coloring->rows) + "x" +
                       std::to_string(coloring->cols) + " net, the project's is " +
                       std::to_string(project.rows) + "x" + std::to_string(project.cols));
    net.coloring = &*coloring;
    net.illumination = project.illumination;
    net.bayer = s->sequence_->experiment().cameras.front().bayer;
  }
  recon::LabelingSetup setup = recon::SetUpLabeling(net);
  s->codebook_ = std::move(setup.codebook);
  s->identity_ = setup.identity;
  s->engine_options_ = setup.options;
  s->cache_ = std::make_unique<recon::FrameCache>(*s->sequence_, cache_options);
  s->document_ = std::make_unique<LabelDocument>(
      OpenLabels(project, s->camera_names_, s->frame_numbers_), project.labels);
  // The missing knots, without those the target hides when the project knows it.
  MissingKnotsOptions missing_options;
  if (!project.target.empty()) {
    s->target_ = LoadTarget(project.target, s->sequence_->experiment().fps);
    missing_options.target = s->target_;
  }
  s->missing_ =
      std::make_unique<MissingKnots>(s->document_.get(), &s->rig_, s->rig_index_, missing_options);
  return s;
}

Session::~Session() {
  engine_.reset();  // it points into the document's store
  missing_.reset();
}

cv::Mat Session::Image(int camera, int t, std::string* error) const {
  const auto image = cache_->Get(camera, frame_numbers_[t], 0, error);
  return image ? *image : cv::Mat();
}

std::unique_ptr<recon::LabelEngine> Session::MakeEngine(recon::LabelStore* store) const {
  auto engine = std::make_unique<recon::LabelEngine>(
      store, &rig_, [this](int c, int t) { return Image(c, t); }, engine_options_);
  if (codebook_) engine->SetCodebook(*codebook_, identity_);
  engine->SetTarget(target_);
  {
    const std::lock_guard<std::mutex> lock(one_path_mutex_);
    engine->AdoptOnePath(one_path_);
  }
  return engine;
}

recon::LabelEngine& Session::engine() {
  if (!engine_) engine_ = MakeEngine(document_->store());
  return *engine_;
}

recon::FindNodeResult Session::FindNode(int camera, int t, int knot, const Eigen::Vector2d& centre,
                                        double radius_px) {
  const recon::FindNodeResult result = engine().FindNodeAt(camera, t, knot, centre, radius_px);
  if (document_->at(camera, t, knot).accepted() && result.status == recon::FindNodeStatus::kFound)
    CheckAgainstPerson(camera, t, knot);
  document_->MergeReasons(engine().reasons());
  return result;
}

void Session::CheckAgainstPerson(int camera, int t, int knot) {
  engine().CheckAgainstPerson(t, knot, {camera});
  document_->MergeReasons(engine().reasons());
}

void Session::PlaceLabel(int camera, int t, int knot, const Eigen::Vector2d& px,
                         const std::string& step) {
  recon::Label label;
  label.px = px;
  label.source = recon::LabelSource::kManual;
  label.confidence = 1.0f;
  label.state = recon::LabelState::kAccepted;
  document_->Apply(step, {{camera, t, knot, label}});
  CheckAgainstPerson(camera, t, knot);
}

void Session::AcceptLabel(int camera, int t, int knot) {
  recon::Label label = document_->at(camera, t, knot);
  if (!label.present()) return;
  label.state = recon::LabelState::kAccepted;
  document_->Apply("Accept", {{camera, t, knot, label}});
  CheckAgainstPerson(camera, t, knot);
}

void Session::DeleteLabel(int camera, int t, int knot) {
  document_->Apply("Delete", {{camera, t, knot, recon::Label{}}});
}

std::string Session::FindPathBetween(int camera, int t, int knot_a, int knot_b) {
  const recon::Label& a = document_->at(camera, t, knot_a);
  const recon::Label& b = document_->at(camera, t, knot_b);
  if (!a.present() || !b.present()) return "both ends of the path must be labeled";
  std::string error;
  const cv::Mat image = Image(camera, t, &error);
  if (image.empty()) return "frame unreadable: " + error;
  const recon::FindPathResult path =
      recon::FindPath(image, project_.cols, knot_a, a.px, knot_b, b.px, engine_options_.detector);
  if (!path.ok) return path.why;
  std::vector<recon::LabelEdit> edits;
  for (size_t i = 0; i < path.knots.size(); ++i) {
    recon::Label label;
    label.px = path.junctions[i].px;
    label.source = recon::LabelSource::kFindPath;
    label.confidence = 1.0f;
    label.state = recon::LabelState::kAccepted;
    edits.push_back({camera, t, path.knots[i], label});
  }
  document_->Apply("Find Path", edits);
  return "";
}

recon::EngineCounts Session::FindPathFromCorners(int t) {
  // One step each (Find Path, then the check): undo takes back the check first.
  recon::EngineCounts counts = engine().LabelFirstFrame(t);
  for (const recon::EngineCounts& more : {engine().CrossCheck(t), engine().FillByPathsAndCheck(t)})
    counts.accepted += more.accepted, counts.review += more.review;
  document_->MergeReasons(engine().reasons());
  NoteLinkLength();
  NoteOnePath();
  return counts;
}

recon::EngineCounts Session::FillGrid(int t) {
  const recon::EngineCounts counts = engine().CrossCheck(t);
  document_->MergeReasons(engine().reasons());
  NoteLinkLength();
  return counts;
}

Session::FillGridPreview Session::PreviewFillGrid(recon::LabelSet snapshot, int t,
                                                  bool from_corners) const {
  FillGridPreview preview;
  preview.t = t;
  preview.from_corners = from_corners;
  // Every label that differs between two sets (every row: the tools touch row t only, but
  // nothing relies on it).
  const auto diff = [this](const recon::LabelSet& before, const recon::LabelSet& after) {
    std::vector<recon::LabelEdit> edits;
    for (int c = 0; c < cameras(); ++c)
      for (int f = 0; f < after.frames(); ++f)
        for (int k = 0; k < after.knots(); ++k)
          if (!recon::SameLabel(before.at(c, f, k), after.at(c, f, k)))
            edits.push_back({c, f, k, after.at(c, f, k)});
    return edits;
  };
  // The same tools on a copy, by an engine that knows what the GUI thread's knows of the net.
  recon::LabelStore store(snapshot);
  const std::unique_ptr<recon::LabelEngine> engine = MakeEngine(&store);
  engine->AdoptLinkLength(link_length_m_.load());
  if (from_corners) {
    engine->LabelFirstFrame(t);
    preview.path_edits = diff(snapshot, store.labels());
    const recon::LabelSet path = store.labels();
    engine->CrossCheck(t);
    engine->FillByPathsAndCheck(t);  // the cameras that saw too few corners, from Fill Grid's
    preview.check_edits = diff(path, store.labels());
  } else {
    engine->CrossCheck(t);
  }
  preview.reasons = engine->reasons();
  preview.link_length_m = engine->link_length_m();
  preview.one_path = engine->one_path();
  preview.edits = diff(snapshot, store.labels());
  // Counted by what the person is asked to look at.
  for (const recon::LabelEdit& e : preview.edits) {
    const recon::Label &was = snapshot.at(e.camera, e.t, e.knot), &now = e.label;
    if (!was.present() && now.present()) {
      ++preview.added;
      preview.added_review += now.state == recon::LabelState::kNeedsReview;
    } else if (was.accepted() && now.present() && now.px == was.px &&
               now.state == recon::LabelState::kNeedsReview) {
      ++preview.to_review;
    } else if (was.present() && was.state == recon::LabelState::kNeedsReview && now.accepted()) {
      ++preview.confirmed;
    } else if (was.accepted() && now.accepted()) {
      ++preview.moved;
    } else {
      ++preview.changed;
    }
  }
  return preview;
}

int Session::ApplyFillGridPreview(const FillGridPreview& preview) {
  // The reasons first: the review queue reads them when the labels change.
  document_->MergeReasons(preview.reasons);
  engine().AdoptLinkLength(preview.link_length_m);
  NoteLinkLength();
  engine().AdoptOnePath(preview.one_path);
  NoteOnePath();
  if (!preview.from_corners) return document_->Apply("Fill Grid", preview.edits);
  return document_->Apply("Find Path from the corners", preview.path_edits) +
         document_->Apply("Fill Grid", preview.check_edits);
}

Session::TrackRun Session::Track(recon::LabelSet snapshot, int from, int to,
                                 const ProgressReporter& progress, int max_review) const {
  TrackRun run;
  run.from = from, run.to = to, run.last_done = from;
  recon::LabelStore store(std::move(snapshot));
  const std::unique_ptr<recon::LabelEngine> engine = MakeEngine(&store);
  const int total = std::abs(to - from);
  engine->TrackFrames(from, to, [&](int t) {
    run.last_done = t;
    progress.Report("frames tracked", std::abs(t - from), total);
    if (progress.cancelled()) {
      run.cancelled = true;
      return false;
    }
    int review = 0;
    for (int c = 0; c < cameras(); ++c)
      for (int k = 0; k < store.labels().knots(); ++k)
        review += store.at(c, t, k).present() &&
                  store.at(c, t, k).state == recon::LabelState::kNeedsReview;
    if (max_review >= 0 && review > max_review) {
      run.stopped_for_review = true;
      return false;
    }
    return true;
  });
  // The rows the run went through, as it left them; applying them changes only what differs
  // (LabelStore::Apply skips a label equal to the one it replaces).
  const int lo = std::min(from, run.last_done), hi = std::max(from, run.last_done);
  for (int c = 0; c < cameras(); ++c)
    for (int t = lo; t <= hi; ++t)
      for (int k = 0; k < store.labels().knots(); ++k)
        run.edits.push_back({c, t, k, store.at(c, t, k)});
  run.reasons = engine->reasons();
  return run;
}

int Session::ApplyTrackRun(const TrackRun& run) {
  document_->MergeReasons(run.reasons);
  const std::string name = "Track frames " + std::to_string(frame_numbers_[run.from]) + "-" +
                           std::to_string(frame_numbers_[run.last_done]);
  return document_->Apply(name, run.edits);
}

std::optional<Session::KnotColours> Session::ExpectedColours(int knot) const {
  if (!codebook_ || knot < 0 || knot >= project_.knots()) return std::nullopt;
  static const char* const kSides[4] = {"right", "down", "left", "up"};
  const std::array<int, 4> around = recon::GridSlots(project_.rows, project_.cols, knot);
  KnotColours out;
  out.read = false;
  // The code's colours run over the knot's links in slot order (CodebookFromColoring).
  const recon::CodebookKnot& code = codebook_->knots[knot];
  int link = 0;
  for (int s = 0; s < 4 && link < code.degree(); ++s) {
    if (around[s] < 0) continue;
    const recon::PaletteColour& dye = codebook_->palette[code.link_colours[link++]];
    out.expected.push_back({kSides[s], dye.name, recon::LinearBgrToSrgb(dye.linear_bgr)});
  }
  return out;
}

std::optional<Session::KnotColours> Session::CheckKnotColours(
    int camera, int t, int knot, const Eigen::Vector2d& px,
    const recon::YarnDirections& yarns) const {
  std::optional<KnotColours> out = ExpectedColours(knot);
  if (!out) return std::nullopt;
  const cv::Mat image = Image(camera, t);
  if (image.empty() || image.type() != CV_8UC3) return std::nullopt;
  const recon::IdentityCheck check =
      recon::CheckIdentity(image, *codebook_, knot, px, yarns, identity_);
  out->read = true;
  out->verdict = check.verdict;
  out->why = check.why;
  out->knots_read = check.knots_read;
  return out;
}

double Session::LinkLengthPx(int camera, int t) const {
  const recon::LabelSet& labels = document_->labels();
  auto median_in = [&](int row) {
    std::vector<double> lengths;
    for (int k = 0; k < project_.knots(); ++k) {
      const recon::Label& a = labels.at(camera, row, k);
      if (!a.accepted()) continue;
      const std::array<int, 4> around = recon::GridSlots(project_.rows, project_.cols, k);
      for (int s = 0; s < 2; ++s) {  // right and down: each link once
        if (around[s] < 0 || !labels.at(camera, row, around[s]).accepted()) continue;
        lengths.push_back((labels.at(camera, row, around[s]).px - a.px).norm());
      }
    }
    if (lengths.empty()) return 0.0;
    std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
    return lengths[lengths.size() / 2];
  };
  for (int d = 0; d < frames(); ++d)
    for (int row : {t - d, t + d}) {
      if (row < 0 || row >= frames() || (d == 0 && row != t)) continue;
      if (const double m = median_in(row); m > 0) return m;
    }
  return 0.0;
}

Session::JunctionHint Session::IdentifyJunction(int camera, int t, const Eigen::Vector2d& centre,
                                                double radius_px, double link_px) const {
  JunctionHint hint;
  if (!codebook_) {
    hint.reading.why = "the project has no colouring: the colours cannot identify a knot";
    return hint;
  }
  std::string error;
  const cv::Mat image = Image(camera, t, &error);
  if (image.empty() || image.type() != CV_8UC3) {
    hint.reading.why = "frame not readable: " + error;
    return hint;
  }
  const recon::FindNodeResult found =
      recon::FindNode(image, centre, radius_px, engine_options_.detector);
  if (found.status != recon::FindNodeStatus::kFound) {
    hint.reading.why =
        found.status == recon::FindNodeStatus::kSeveral
            ? "several junctions in the brush: point at one"
            : "no junction in the brush" + (found.why.empty() ? "" : ": " + found.why);
    return hint;
  }
  hint.found = true;
  hint.px = found.knot.px;
  hint.corner_mass = found.knot.solid;
  hint.link_px = link_px < 0 ? LinkLengthPx(camera, t) : link_px;
  // Knots labeled elsewhere in this view are not this one.
  std::vector<int> exclude;
  const recon::LabelSet& labels = document_->labels();
  for (int k = 0; k < project_.knots(); ++k) {
    const recon::Label& l = labels.at(camera, t, k);
    if (l.accepted() && (l.px - hint.px).norm() > radius_px) exclude.push_back(k);
  }
  const int n = static_cast<int>(found.knot.branch_angles_rad.size());
  if (n >= 2 && n <= 4)
    hint.reading = recon::ReadJunctionIdentity(
        image, *codebook_, hint.px, found.knot.branch_angles_rad, hint.link_px, identity_, exclude);
  else
    hint.reading.why = std::to_string(n) + " yarns leave the junction: its colours are not read";
  if (hint.corner_mass) {
    // A corner mass is one of the four corners: keep those the colours allow (all four when they
    // say nothing).
    const int rows = project_.rows, cols = project_.cols;
    const std::array<int, 4> corners = {0, cols - 1, (rows - 1) * cols, rows * cols - 1};
    std::vector<int> offered;
    const bool read = hint.reading.status != recon::IdentifyStatus::kUnknown;
    for (int k : corners)
      if (std::find(exclude.begin(), exclude.end(), k) == exclude.end() &&
          (!read || std::find(hint.reading.knots.begin(), hint.reading.knots.end(), k) !=
                        hint.reading.knots.end()))
        offered.push_back(k);
    const bool sure = offered.size() == 1 && read &&
                      hint.reading.yarns_certain >= std::min(identity_.min_certain_yarns, 2);
    hint.reading.knots = offered;
    hint.reading.status = offered.empty() ? recon::IdentifyStatus::kUnknown
                          : sure          ? recon::IdentifyStatus::kIdentified
                                          : recon::IdentifyStatus::kAmbiguous;
    hint.reading.why = "a corner mass: " +
                       (offered.empty() ? std::string("every corner is labeled elsewhere")
                                        : std::to_string(offered.size()) + " corner(s) possible") +
                       "; colours: " + hint.reading.why;
  }
  return hint;
}

recon::PointEstimate Session::Triangulate(int t, int knot) const {
  std::vector<recon::Observation> obs;
  for (int c = 0; c < cameras(); ++c)
    if (document_->at(c, t, knot).accepted())
      obs.push_back({rig_index_[c], document_->at(c, t, knot).px});
  if (obs.size() < 2) {
    recon::PointEstimate none;
    none.why = "labeled in fewer than two cameras";
    return none;
  }
  return recon::TriangulatePoint(rig_, obs);
}

std::vector<std::vector<Eigen::Vector2d>> Session::EpipolarCurve(int from,
                                                                 const Eigen::Vector2d& px,
                                                                 int to) const {
  const calib::Camera& a = rig_camera(from);
  const calib::Camera& b = rig_camera(to);
  std::vector<std::vector<Eigen::Vector2d>> pieces(1);
  const Eigen::Vector2d xy = calib::UndistortPoint(a.intrinsics, px);
  if (!xy.allFinite()) return {};
  // The viewing ray in the world, sampled at depths spaced evenly in 1 / depth (even in the
  // other image, roughly), each point projected through b's lens.
  const calib::Rigid3d world_from_a = a.cam_from_world.Inverse();
  constexpr int kSamples = 160;
  constexpr double kNear = 0.2, kFar = 20.0;  // m
  for (int i = 0; i <= kSamples; ++i) {
    const double inverse = 1.0 / kNear + (1.0 / kFar - 1.0 / kNear) * i / kSamples;
    const Eigen::Vector3d p_in_a = Eigen::Vector3d(xy.x(), xy.y(), 1.0) / inverse;
    const Eigen::Vector2d q = b.ProjectWorld(world_from_a * p_in_a);
    const bool inside = q.allFinite() && q.x() >= -0.5 && q.y() >= -0.5 &&
                        q.x() <= b.intrinsics.width - 0.5 && q.y() <= b.intrinsics.height - 0.5;
    if (inside)
      pieces.back().push_back(q);
    else if (!pieces.back().empty())
      pieces.emplace_back();
  }
  if (pieces.back().empty()) pieces.pop_back();
  return pieces;
}

// ---------------------------------------------------------------------------------------------
// Hidden marks.

int Session::MarkHidden(int camera, int t, int knot) {
  return document_->Apply("Mark hidden", {{camera, t, knot, recon::Label::Hidden()}});
}

int Session::MarkHiddenRun(int camera, int t, int knot) {
  const std::vector<int> run = missing_->RunFrom(camera, t, knot);
  if (run.empty()) return -1;
  std::vector<recon::LabelEdit> edits;
  for (int u : run) edits.push_back({camera, u, knot, recon::Label::Hidden()});
  document_->Apply("Mark hidden in frames " + std::to_string(frame_numbers_[run.front()]) + "-" +
                       std::to_string(frame_numbers_[run.back()]),
                   edits);
  return run.back();
}

}  // namespace netlab::gui
