#include "app/gui/document/missing_knots.h"

#include <yaml-cpp/yaml.h>

#include <stdexcept>

#include "common/errors.h"
#include "common/tracks/track_file.h"
#include "libnetsim/scenario/scenario.h"

namespace netlab::gui {

recon::Target LoadTarget(const std::string& path, double fps) {
  // The scenario's text: the file itself, or a simulation result's /scenario.
  const bool result = path.size() > 3 && path.compare(path.size() - 3, 3, ".h5") == 0;
  std::string text;
  try {
    text = result ? ReadKnotTracks(path).scenario : netsim::ReadScenarioText(path);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path + ": cannot be read as the target (" + e.what() + ")");
  }
  if (text.empty())
    throw InputError(path +
                     ": no /scenario (the target is a scenario file or a netlab simulate "
                     "result)");
  // Only the bodies matter: the data files the scenario names (gravity, frame rotation, drag)
  // are not read.
  const std::string origin = result ? path + ":/scenario" : path;
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(origin + ": " + e.what());
  }
  if (!root.IsMap()) throw InputError(origin + ": not a scenario (expected a mapping)");
  for (const char* key : {"gravity", "rotating_frame", "drag"}) root.remove(key);
  YAML::Emitter emitter;
  emitter << root;
  netsim::Scenario scenario;
  try {
    scenario = netsim::ParseScenario(emitter.c_str(), origin, "");
  } catch (const InputError& e) {
    throw InputError(std::string("the target is no scenario: ") + e.what());
  }
  recon::Target target;
  target.fps = fps;
  for (const netsim::RigidBody& body : scenario.bodies) {
    recon::TargetSolid solid;
    solid.center = body.center;
    solid.velocity = body.velocity;
    if (body.shape == netsim::RigidBody::Shape::kBox) {
      solid.orientation = body.orientation;
      solid.half_extents = body.half_extents;
    } else if (body.shape == netsim::RigidBody::Shape::kSphere) {
      solid.shape = recon::TargetSolid::Shape::kSphere;
      solid.radius = body.radius;
    } else {
      continue;  // a plane (a wall, a floor) is no target
    }
    target.solids.push_back(solid);
  }
  if (target.empty())
    throw InputError(origin + ": no box or sphere among its bodies: nothing to be the target");
  return target;
}

MissingKnots::MissingKnots(const LabelDocument* document, const calib::Rig* rig,
                           std::vector<int> rig_index, MissingKnotsOptions options, QObject* parent)
    : QObject(parent),
      document_(document),
      rig_(rig),
      rig_index_(std::move(rig_index)),
      options_(options) {
  std::string why;
  if (!options_.IsValid(&why)) throw std::invalid_argument("missing knots: " + why);
  if (rig_index_.size() != document_->labels().cameras.size())
    throw std::invalid_argument("missing knots: one rig camera per camera of the labels");
  // Every frame row now; later only the rows an edit names.
  const int frames = document_->labels().frames();
  by_row_.resize(frames);
  for (int t = 0; t < frames; ++t) {
    by_row_[t] = FindMissingKnots(document_->labels(), *rig_, rig_index_, t, options_);
    size_ += static_cast<int>(by_row_[t].size());
  }
  connect(document_, &LabelDocument::labelsChanged, this, &MissingKnots::Recount);
}

void MissingKnots::Recount(const QList<int>& frames) {
  // A row's points also place the knots of the rows around it (their motion).
  std::set<int> rows;
  for (int t : frames)
    for (int s = t - options_.motion_rows; s <= t + options_.motion_rows; ++s)
      if (s >= 0 && s < static_cast<int>(by_row_.size())) rows.insert(s);
  QList<int> counted;
  for (int t : rows) {
    size_ -= static_cast<int>(by_row_[t].size());
    by_row_[t] = FindMissingKnots(document_->labels(), *rig_, rig_index_, t, options_);
    size_ += static_cast<int>(by_row_[t].size());
    counted.append(t);
  }
  emit changed(counted);
}

std::vector<LabelKey> MissingKnots::Items() const {
  std::vector<LabelKey> items;
  items.reserve(size_);
  for (const std::vector<MissingKnot>& row : by_row_)
    for (const MissingKnot& m : row) items.emplace_back(m.camera, m.t, m.knot);
  return items;
}

const MissingKnot* MissingKnots::Find(int camera, int t, int knot) const {
  if (t < 0 || t >= static_cast<int>(by_row_.size())) return nullptr;
  for (const MissingKnot& m : by_row_[t])
    if (m.camera == camera && m.knot == knot) return &m;
  return nullptr;
}

std::string MissingKnots::Reason(int camera, int t, int knot) const {
  const MissingKnot* m = Find(camera, t, knot);
  return m ? MissingReason(*m, document_->labels().cameras, document_->labels().frame_index) : "";
}

std::set<int> MissingKnots::Frames() const {
  std::set<int> frames;
  for (int t = 0; t < static_cast<int>(by_row_.size()); ++t)
    if (!by_row_[t].empty()) frames.insert(t);
  return frames;
}

std::vector<int> MissingKnots::RunFrom(int camera, int t, int knot) const {
  std::vector<int> run;
  for (int u = t; Find(camera, u, knot); ++u) run.push_back(u);
  return run;
}

}  // namespace netlab::gui
