#include "app/gui/document/simulation_presenter.h"

#include <unistd.h>

#include <QFileInfo>
#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <mutex>
#include <stdexcept>

#include "app/gui/document/project.h"
#include "app/gui/document/reconstruction_presenter.h"
#include "app/gui/document/session.h"
#include "common/errors.h"
#include "common/files.h"
#include "common/hdf5_util.h"
#include "common/yaml_util.h"
#include "libnetsim/identification/fit_file.h"
#include "libnetsim/scenario/run_scenario.h"
#include "libnetsim/validation/score_file.h"
#include "libnetsim/validation/score_report.h"

namespace netlab::gui {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A name for files: the simulation's file name without its extension, safe characters only.
std::string Stem(const std::string& path) {
  std::string stem = std::filesystem::path(path).stem().string();
  for (char& ch : stem)
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '_' && ch != '-') ch = '_';
  return stem.empty() ? "sim" : stem;
}

QString Seconds(double s) {
  return s < 90 ? QString("%1 s").arg(s, 0, 'f', 0) : QString("%1 min").arg(s / 60, 0, 'f', 1);
}

}  // namespace

std::optional<Eigen::Vector2d> SimulatedView::Find(int knot) const {
  for (size_t i = 0; i < knots.size(); ++i)
    if (knots[i] == knot) return px[i];
  return std::nullopt;
}

SimulationPresenter::SimulationPresenter(const Session* session,
                                         const ReconstructionPresenter* reconstruction)
    : session_(session), reconstruction_(reconstruction) {}

SimulationJob SimulationPresenter::MakeSimulationJob(const std::string& scenario_path,
                                                     const std::vector<std::string>& overrides,
                                                     const std::string& out_path,
                                                     double duration_s) {
  SimulationJob job;
  job.scenario_path = scenario_path;
  for (const std::string& text : overrides) job.overrides.push_back(netsim::ParseOverride(text));
  job.out_path = out_path;
  job.duration_s = duration_s;
  return job;
}

SimulationRun SimulationPresenter::Simulate(const SimulationJob& job,
                                            const ProgressReporter& progress) {
  const auto start = std::chrono::steady_clock::now();
  SimulationRun run;
  run.path = job.out_path;
  try {
    netsim::Scenario scenario = netsim::LoadScenario(job.scenario_path, job.overrides);
    if (job.duration_s > 0) scenario.duration = job.duration_s;
    netsim::RunOptions options;
    options.out_path = job.out_path;
    options.progress = progress;
    // A cancelled or failed run leaves no file (and job.out_path as it was).
    OutputSet outputs({job.out_path});
    const netsim::RunSummary summary = netsim::RunScenario(scenario, options);
    if (!summary.stable) {
      run.error = job.scenario_path + ": the run stopped: " + summary.error;
    } else {
      outputs.Commit();
      run.tracks = ReadKnotTracks(job.out_path);
    }
  } catch (const Cancelled&) {
    run.cancelled = true;
  } catch (const std::exception& e) {
    run.error = e.what();
  }
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

SimulationRun SimulationPresenter::Load(const std::string& path) {
  SimulationRun run;
  run.path = path;
  try {
    run.tracks = ReadKnotTracks(path);
  } catch (const std::exception& e) {
    run.error = e.what();
  }
  return run;
}

int SimulationPresenter::Add(SimulationRun run) {
  if (!run.tracks) return -1;
  Simulation s;
  s.path = run.path;
  s.name = std::filesystem::path(run.path).filename().string();
  s.tracks = std::move(*run.tracks);
  simulations_.push_back(std::move(s));
  return simulations() - 1;
}

void SimulationPresenter::AddToProject(int i) const {
  Project project = LoadProject(session_->project().path);
  const std::string path = std::filesystem::absolute(simulations_.at(i).path).lexically_normal();
  for (const std::string& s : project.simulations)
    if (s == path) return;
  project.simulations.push_back(path);
  SaveProject(project, project.path);
}

std::vector<std::string> SimulationPresenter::OpenFromProject(
    ReconstructionPresenter* reconstruction) {
  std::vector<std::string> errors;
  Project project;
  try {
    project = LoadProject(session_->project().path);  // as saved now
  } catch (const std::exception& e) {
    return {e.what()};
  }
  if (!project.tracks.empty() && reconstruction->tracks() == nullptr) {
    try {
      reconstruction->LoadTracks(project.tracks);
    } catch (const std::exception& e) {
      errors.push_back(e.what());
    }
  }
  for (const std::string& path : project.simulations) {
    bool here = false;
    for (const Simulation& s : simulations_) here = here || s.path == path;
    if (here) continue;
    SimulationRun run = Load(path);
    if (!run.tracks) errors.push_back(run.error);
    Add(std::move(run));
  }
  // The score files the project names (the room scores its simulations again on opening and
  // writes them anew); the last fit.
  for (const ProjectScore& score : project.scores)
    for (Simulation& s : simulations_)
      if (s.path == score.simulation && s.score_path.empty()) {
        s.score_path = score.score;
        s.report_path = score.report;
      }
  if (!project.fits.empty() && !fit_) fit_path_ = project.fits.back();
  return errors;
}

const KnotTracks* SimulationPresenter::measured() const {
  return reconstruction_ ? reconstruction_->tracks() : nullptr;
}

ScoreJob SimulationPresenter::MakeScoreJob(int i, netsim::Alignment alignment) const {
  if (measured() == nullptr) throw std::logic_error("no measured tracks: triangulate first");
  ScoreJob job;
  job.index = i;
  job.measured = *measured();
  job.sim = simulations_.at(i).tracks;
  job.options.alignment = alignment;
  job.measured_name = "the triangulated labels";
  job.sim_name = simulations_[i].path;
  return job;
}

ScoreRun SimulationPresenter::RunScore(const ScoreJob& job) {
  ScoreRun run;
  run.index = job.index;
  try {
    const auto start = std::chrono::steady_clock::now();
    run.result = netsim::Score(job.measured, job.sim, job.options, job.measured_name, job.sim_name);
    run.result->summary.wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  } catch (const std::exception& e) {
    run.error = e.what();
  }
  return run;
}

void SimulationPresenter::SetScore(ScoreRun run, const std::string& folder) {
  if (run.index < 0 || run.index >= simulations()) return;
  Simulation& s = simulations_[run.index];
  s.score = std::move(run.result);
  s.score_error = run.error;
  s.score_path.clear();
  s.report_path.clear();
  if (!s.score || folder.empty()) return;
  const std::string stem = (std::filesystem::path(folder) / ("score_" + Stem(s.path))).string();
  try {
    OutputSet outputs({stem + ".h5", stem + ".html"});
    netsim::WriteScore(stem + ".h5", *s.score);
    netsim::ReportInfo info;
    info.measured_path = "the labels of " + session_->project().labels + ", triangulated";
    info.sim_path = s.path;
    info.score_path = stem + ".h5";
    netsim::WriteScoreReport(stem + ".html", *s.score, info);
    outputs.Commit();
    s.score_path = stem + ".h5";
    s.report_path = stem + ".html";
  } catch (const std::exception& e) {
    s.score_error = std::string("scored, but the files could not be written: ") + e.what();
    return;
  }
  try {
    Project project = LoadProject(session_->project().path);
    const ProjectScore entry{std::filesystem::absolute(s.path).lexically_normal().string(),
                             s.score_path, s.report_path};
    auto same = [&](const ProjectScore& p) { return p.simulation == entry.simulation; };
    project.scores.erase(std::remove_if(project.scores.begin(), project.scores.end(), same),
                         project.scores.end());
    project.scores.push_back(entry);
    SaveProject(project, project.path);
  } catch (const std::exception& e) {
    s.score_error = std::string("scored, but not named in the project: ") + e.what();
  }
}

void SimulationPresenter::SetFit(FitRun run, const std::string& folder) {
  fit_ = std::move(run);
  if (!fit_->result || folder.empty()) return;
  const std::string path =
      (std::filesystem::path(folder) / ("fit_" + Stem(fit_->scenario_path) + ".yaml")).string();
  try {
    Project project = LoadProject(session_->project().path);
    netsim::WriteFit(path, {fit_->scenario_path}, {project.tracks}, *fit_->result);
    fit_path_ = path;
    const std::string absolute = std::filesystem::absolute(path).lexically_normal().string();
    if (std::find(project.fits.begin(), project.fits.end(), absolute) == project.fits.end()) {
      project.fits.push_back(absolute);
      SaveProject(project, project.path);
    }
  } catch (const std::exception& e) {
    fit_->result->notes.push_back(std::string("fitted, but not saved: ") + e.what());
  }
}

QString SimulationPresenter::FitFileText(const std::string& path) {
  try {
    const YAML::Node root = LoadYamlFile(path);
    QString text = QString("Fit read from %1:").arg(QString::fromStdString(path));
    for (auto it = root["parameters"].begin(); it != root["parameters"].end(); ++it) {
      const YAML::Node p = it->second;
      text += QString("\n  %1 = %2 ± %3 %4 (%5)")
                  .arg(QString::fromStdString(it->first.as<std::string>()))
                  .arg(QString::fromStdString(p["value"].as<std::string>()))
                  .arg(QString::fromStdString(p["sigma"].as<std::string>()))
                  .arg(QString::fromStdString(p["units"].as<std::string>("")))
                  .arg(p["identified"].as<bool>(false)
                           ? "identified by the " +
                                 QString::fromStdString(p["determined_by"].as<std::string>(""))
                           : QString("not identified"));
    }
    text += QString("\nCost %1 → %2 in %3 iterations, %4 simulations.")
                .arg(QString::fromStdString(root["cost_initial"].as<std::string>("?")))
                .arg(QString::fromStdString(root["cost_final"].as<std::string>("?")))
                .arg(QString::fromStdString(root["iterations"].as<std::string>("?")))
                .arg(QString::fromStdString(root["simulations"].as<std::string>("?")));
    if (const YAML::Node score = root["score"])
      text += QString("\nThe fitted model: %1, RMS %2 mm, mean d² %3.")
                  .arg(QString::fromStdString(score["verdict"].as<std::string>("?")))
                  .arg(QString::fromStdString(score["rms_mm"].as<std::string>("?")))
                  .arg(QString::fromStdString(score["mean_d2"].as<std::string>("?")));
    return text;
  } catch (const std::exception& e) {
    return QString("The project's fit cannot be read: ") + e.what();
  }
}

QString SimulationPresenter::Verdict(int i) const {
  const Simulation& s = simulations_.at(i);
  if (!s.score) {
    if (!s.score_error.empty()) return "Not scored: " + QString::fromStdString(s.score_error);
    return "Not scored yet.";
  }
  const netsim::ScoreSummary& m = s.score->summary;
  const bool consistent = m.verdict == netsim::Verdict::kConsistent;
  QString text =
      QString("%1: %2 (mean d² %3 %4 the critical %5, p = %6, over %7 knot-frames).")
          .arg(QString::fromStdString(netsim::VerdictName(m.verdict)))
          .arg(consistent ? "the simulated net lies where the cameras saw the real one, within "
                            "the measurement's uncertainty"
                          : "the simulated net is not where the cameras saw the real one: the "
                            "differences are larger than the measurement's uncertainty allows")
          .arg(m.mean_d2, 0, 'g', 3)
          .arg(consistent ? "within" : "above")
          .arg(m.critical_mean_d2, 0, 'g', 3)
          .arg(m.p_value, 0, 'g', 2)
          .arg(m.points);
  text += "\n" + QString::fromStdString(m.headline);
  QString aligned = QString("Aligned: %1, time offset %2 ms")
                        .arg(QString::fromStdString(netsim::AlignmentName(m.alignment)))
                        .arg(m.time_offset_s * 1e3, 0, 'f', 2);
  if (m.alignment == netsim::Alignment::kRigid || m.alignment == netsim::Alignment::kTimeAndRigid)
    aligned += QString(", moved %1 mm").arg(m.translation.norm() * 1e3, 0, 'f', 1);
  text += "\n" + aligned + ".";
  if (!s.score_error.empty()) text += "\n" + QString::fromStdString(s.score_error);
  return text;
}

FitJob SimulationPresenter::MakeFitJob(const std::string& scenario_path,
                                       const std::vector<std::string>& overrides,
                                       const std::string& free) const {
  if (measured() == nullptr) throw std::logic_error("no measured tracks: triangulate first");
  FitJob job;
  job.scenario_path = scenario_path;
  for (const std::string& text : overrides) job.options.set.push_back(netsim::ParseOverride(text));
  job.options.score.max_time_offset_s = 0.05;  // as netlab fit
  job.options.jobs = 2;
  job.parameters = netsim::ParseFreeParameters(free, scenario_path, job.options.set,
                                               job.options.score.time_offset_s);
  job.measured = *measured();
  return job;
}

FitRun SimulationPresenter::Fit(const FitJob& job, const ProgressReporter& progress) {
  FitRun run;
  run.scenario_path = job.scenario_path;
  if (progress.cancelled()) {
    run.cancelled = true;
    return run;
  }
  netsim::FitOptions options = job.options;
  options.progress = progress;
  try {
    run.result = netsim::FitShot(job.scenario_path, job.measured, job.parameters, options,
                                 "the triangulated labels");
  } catch (const Cancelled&) {
    run.cancelled = true;
  } catch (const std::exception& e) {
    run.error = e.what();
  }
  if (!run.result) return run;
  // The start: simulated once (to a file of its own, removed after) and scored as the fitted
  // model is, against the same tracks with the fit's score options.
  progress.Report("the start", run.result->simulations, run.result->simulations,
                  "simulating and scoring the scenario with its overrides");
  static std::atomic<int> starts{0};
  const std::string out =
      (std::filesystem::temp_directory_path() /
       ("netlab_fit_start_" + std::to_string(getpid()) + "_" + std::to_string(starts++) + ".h5"))
          .string();
  const SimulationRun start =
      Simulate({job.scenario_path, job.options.set, out, 0.0}, progress.Silent());
  std::error_code ignored;
  std::filesystem::remove(out, ignored);
  if (start.cancelled) {
    run.start_error = "cancelled";
  } else if (!start.tracks) {
    run.start_error = start.error;
  } else {
    try {
      run.start_score = netsim::Score(job.measured, *start.tracks, job.options.score,
                                      "the triangulated labels", "the start")
                            .summary;
    } catch (const std::exception& e) {
      run.start_error = e.what();
    }
  }
  return run;
}

QString SimulationPresenter::ProgressText(const Progress& p, double elapsed_s) {
  QString text;
  if (!p.stage.empty()) text += QString::fromStdString(p.stage) + ", ";
  const double eta_s = p.done > 0 ? elapsed_s / p.done * (p.total - p.done) : 0.0;
  return text + QString("%1, %2 simulations, %3, ETA at most %4")
                    .arg(QString::fromStdString(p.detail))
                    .arg(static_cast<long>(p.done))
                    .arg(Seconds(elapsed_s))
                    .arg(Seconds(eta_s));
}

QString SimulationPresenter::FitText() const {
  if (!fit_) return fit_path_.empty() ? QString() : FitFileText(fit_path_);
  if (fit_->cancelled) return "Fit cancelled.";
  if (!fit_->result) return "Fit failed: " + QString::fromStdString(fit_->error);
  const netsim::FitResult& r = *fit_->result;
  QString text = "Fitted:";
  for (const netsim::FittedParameter& f : r.parameters) {
    const QString sigma = std::isfinite(f.sigma) ? QString::number(f.sigma, 'g', 3) : "∞";
    QString verdict = f.identified
                          ? "identified by the " +
                                QString::fromStdString(netsim::DeterminedByName(f.determined_by))
                      : f.determined_by == netsim::DeterminedBy::kPrior ? QString("from its prior")
                                                                        : QString("not identified");
    if (f.rough) verdict += "; the cost is rough there: σ means little";
    if (f.ambiguous) verdict += QString("; another valley at %1").arg(f.alternative, 0, 'g', 4);
    text += QString("\n  %1 = %2 ± %3 %4 (%5)")
                .arg(QString::fromStdString(f.parameter.name))
                .arg(f.value, 0, 'g', 5)
                .arg(sigma)
                .arg(QString::fromStdString(f.parameter.units))
                .arg(verdict);
  }
  text += QString("\nCost %1 → %2 in %3 iterations, %4 simulations, %5.")
              .arg(r.cost_initial, 0, 'g', 5)
              .arg(r.cost_final, 0, 'g', 5)
              .arg(r.iterations)
              .arg(r.simulations)
              .arg(Seconds(r.wall_s));
  text += QString("\nThe fitted model: %1, RMS %2 mm, mean d² %3.")
              .arg(QString::fromStdString(netsim::VerdictName(r.score.verdict)))
              .arg(r.score.rms_m * 1e3, 0, 'g', 3)
              .arg(r.score.mean_d2, 0, 'g', 3);
  if (fit_->start_score) {
    const netsim::ScoreSummary& s = *fit_->start_score;
    text += QString("\nThe start (the scenario with its overrides): %1, RMS %2 mm, mean d² %3.")
                .arg(QString::fromStdString(netsim::VerdictName(s.verdict)))
                .arg(s.rms_m * 1e3, 0, 'g', 3)
                .arg(s.mean_d2, 0, 'g', 3);
  } else {
    text += "\nThe start not scored: " + QString::fromStdString(fit_->start_error);
  }
  for (const std::string& note : r.notes) text += "\nnote: " + QString::fromStdString(note);
  return text;
}

namespace {

// The scenario's main keys as (dotted path, value) rows: the scalars and short lists of the
// sections a person changes (net, materials, launch, target, drag, integrator, time).
void Flatten(const YAML::Node& node, const std::string& path,
             std::vector<std::pair<std::string, std::string>>* rows) {
  if (node.IsScalar()) {
    rows->emplace_back(path, node.as<std::string>());
  } else if (node.IsSequence()) {
    bool scalars = true;
    for (const YAML::Node& item : node) scalars = scalars && item.IsScalar();
    if (scalars) {
      YAML::Emitter out;
      out << YAML::Flow << node;
      rows->emplace_back(path, out.c_str());
      return;
    }
    for (size_t i = 0; i < node.size(); ++i) Flatten(node[i], path + "." + std::to_string(i), rows);
  } else if (node.IsMap()) {
    for (auto it = node.begin(); it != node.end(); ++it)
      Flatten(it->second,
              path.empty() ? it->first.as<std::string>() : path + "." + it->first.as<std::string>(),
              rows);
  }
}

}  // namespace

std::vector<std::pair<std::string, std::string>> SimulationPresenter::ScenarioKeys(
    const std::string& path) {
  std::vector<std::pair<std::string, std::string>> rows;
  const YAML::Node root = LoadYamlFile(path);
  for (const char* key :
       {"duration", "integrator", "drag", "gravity", "materials", "nets", "bodies"})
    if (root[key]) Flatten(root[key], key, &rows);
  return rows;
}

std::string SimulationPresenter::CheckScenario(const std::string& path,
                                               const std::vector<std::string>& overrides) {
  try {
    std::vector<netsim::ScenarioOverride> parsed;
    for (const std::string& text : overrides) parsed.push_back(netsim::ParseOverride(text));
    netsim::LoadScenario(path, parsed);  // every check of netlab simulate's
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

double SimulationPresenter::FrameTime(int t) const {
  const KnotTracks* m = measured();
  const int row = reconstruction_ ? reconstruction_->TrackRow(t) : -1;
  if (m != nullptr && row >= 0) return m->time[row];
  return session_->frame_number(t) / session_->fps();
}

double SimulationPresenter::time_offset_s(int i) const {
  const Simulation& s = simulations_.at(i);
  return s.score ? s.score->summary.time_offset_s : 0.0;
}

std::vector<Eigen::Vector3d> SimulationPresenter::KnotsAt(int i, double time_s) const {
  const Simulation& s = simulations_.at(i);
  const KnotTracks& sim = s.tracks;
  const int rows = session_->project().rows, cols = session_->project().cols;
  std::vector<Eigen::Vector3d> out(rows * cols, Eigen::Vector3d::Constant(kNaN));
  const int n = sim.frames();
  if (n == 0 || time_s < sim.time.front() || time_s > sim.time.back()) return out;
  // The score's interpolant: 4-point Lagrange on the stored frames around the time (fewer at
  // the ends of the run).
  const int upper = static_cast<int>(std::upper_bound(sim.time.begin(), sim.time.end(), time_s) -
                                     sim.time.begin());
  const int points = std::min(4, n);
  const int first = std::clamp(upper - 2, 0, n - points);
  std::vector<double> weight(points);
  for (int a = 0; a < points; ++a) {
    double w = 1.0;
    for (int b = 0; b < points; ++b)
      if (b != a) w *= (time_s - sim.time[first + b]) / (sim.time[first + a] - sim.time[first + b]);
    weight[a] = w;
  }
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  if (s.score) {
    rotation = s.score->summary.rotation;
    translation = s.score->summary.translation;
  }
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const int k = sim.FindKnot(r, c);
      if (k < 0) continue;
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      bool valid = true;
      for (int a = 0; a < points; ++a) {
        valid = valid && sim.Valid(first + a, k);
        p += weight[a] * sim.Position(first + a, k);
      }
      if (valid) out[r * cols + c] = rotation * p + translation;
    }
  return out;
}

SimulatedView SimulationPresenter::InCamera(int i, int c, int t) const {
  SimulatedView view;
  view.sim_time_s = FrameTime(t) + time_offset_s(i);
  const std::vector<Eigen::Vector3d> knots = KnotsAt(i, view.sim_time_s);
  const calib::Camera& camera = session_->rig_camera(c);
  const int rows = session_->project().rows, cols = session_->project().cols;
  std::vector<std::optional<Eigen::Vector2d>> px(knots.size());
  for (size_t k = 0; k < knots.size(); ++k) {
    if (!knots[k].allFinite()) continue;
    if ((camera.cam_from_world * knots[k]).z() <= 1e-6) continue;  // behind the camera
    const Eigen::Vector2d p = camera.ProjectWorld(knots[k]);
    if (!p.allFinite()) continue;
    px[k] = p;
    view.knots.push_back(static_cast<int>(k));
    view.px.push_back(p);
  }
  for (int r = 0; r < rows; ++r)
    for (int col = 0; col < cols; ++col) {
      const int k = r * cols + col;
      if (!px[k]) continue;
      if (col + 1 < cols && px[k + 1]) view.links.emplace_back(*px[k], *px[k + 1]);
      if (r + 1 < rows && px[k + cols]) view.links.emplace_back(*px[k], *px[k + cols]);
    }
  return view;
}

std::optional<double> SimulationPresenter::LabelDistancePx(int i, int c, int t, int knot) const {
  const recon::Label& label = session_->document().labels().at(c, t, knot);
  if (!label.present()) return std::nullopt;
  const std::optional<Eigen::Vector2d> sim = InCamera(i, c, t).Find(knot);
  if (!sim) return std::nullopt;
  return (label.px - *sim).norm();
}

std::vector<double> SimulationPresenter::ShownKnotErrorsMm(QString* source) const {
  const int rows = session_->project().rows, cols = session_->project().cols;
  std::string sim_path, score_path;
  if (shown_ >= 0 && shown_ < simulations()) {
    const Simulation& s = simulations_[shown_];
    sim_path = s.path;
    score_path = s.score_path;
    if (s.score) {
      const netsim::ScoreResult& r = *s.score;
      std::vector<double> errors(rows * cols, kNaN);
      for (size_t k = 0; k < r.grid.size() && k < r.summary.per_knot.size(); ++k) {
        const auto [row, col] = r.grid[k];
        if (row >= 0 && row < rows && col >= 0 && col < cols)
          errors[row * cols + col] = r.summary.per_knot[k].rms_m * 1e3;
      }
      if (source != nullptr) *source = "RMS error against " + QString::fromStdString(s.name);
      return errors;
    }
  } else {
    sim_path = SavedScoreSimulation();
    for (const ProjectScore& p : session_->project().scores)
      if (p.simulation == sim_path) score_path = p.score;
  }
  if (score_path.empty()) return {};
  const SavedErrors& saved = ReadSavedErrors(score_path);
  if (source != nullptr)
    *source =
        saved.error.empty()
            ? "RMS error against " +
                  QString::fromStdString(std::filesystem::path(sim_path).filename().string()) +
                  " (saved)"
            : QString::fromStdString(saved.error);
  return saved.mm;
}

std::string SimulationPresenter::SavedScoreSimulation() const {
  const Project& project = session_->project();
  for (const std::string& sim : project.simulations)
    for (const ProjectScore& p : project.scores)
      if (p.simulation == sim && !p.score.empty()) return sim;
  return "";
}

std::string SimulationPresenter::SavedScoreAlignment() const {
  const std::string sim = SavedScoreSimulation();
  for (const ProjectScore& p : session_->project().scores)
    if (!sim.empty() && p.simulation == sim) return ReadSavedErrors(p.score).alignment;
  return "";
}

const SimulationPresenter::SavedErrors& SimulationPresenter::ReadSavedErrors(
    const std::string& score_path) const {
  if (saved_errors_ && saved_errors_->score_path == score_path) return *saved_errors_;
  saved_errors_ = SavedErrors{score_path, {}, "", ""};
  const int rows = session_->project().rows, cols = session_->project().cols;
  try {
    const std::lock_guard<std::mutex> lock(h5::Mutex());
    const h5::Id file = h5::OpenFileReadOnly(score_path);
    const std::vector<hsize_t> grid_dims = h5::DatasetDims(file.get(), "/knots/grid");
    const std::vector<hsize_t> rms_dims = h5::DatasetDims(file.get(), "/knots/rms_m");
    if (grid_dims.size() != 2 || grid_dims[1] != 2 || rms_dims.size() != 1 ||
        rms_dims[0] != grid_dims[0])
      throw std::runtime_error("/knots/grid is not [K, 2] beside /knots/rms_m [K]");
    const size_t knots = rms_dims[0];
    std::vector<int> grid(2 * knots);
    std::vector<double> rms(knots);
    h5::ReadDataset(file.get(), "/knots/grid", H5T_NATIVE_INT, grid.data());
    h5::ReadDataset(file.get(), "/knots/rms_m", H5T_NATIVE_DOUBLE, rms.data());
    const double to_m = h5::UnitsFactor(file.get(), score_path, "/knots/rms_m", h5::kMetres);
    std::vector<double> mm(rows * cols, kNaN);
    for (size_t k = 0; k < knots; ++k) {
      const int row = grid[2 * k], col = grid[2 * k + 1];
      if (row < 0 || row >= rows || col < 0 || col >= cols)
        throw std::runtime_error("/knots/grid's knot (" + std::to_string(row) + "," +
                                 std::to_string(col) + ") is not on the project's " +
                                 std::to_string(rows) + " x " + std::to_string(cols) + " net");
      mm[row * cols + col] = rms[k] * to_m * 1e3;
    }
    saved_errors_->mm = std::move(mm);
    saved_errors_->alignment = h5::ReadStringAttribute(file.get(), "alignment");
  } catch (const std::exception& e) {
    saved_errors_->error = "the saved score " + score_path + " cannot be read: " + e.what();
  }
  return *saved_errors_;
}

std::optional<double> SimulationPresenter::ResidualM(int i, int t, int knot) const {
  const Simulation& s = simulations_.at(i);
  const int row = reconstruction_ ? reconstruction_->TrackRow(t) : -1;
  if (!s.score || row < 0) return std::nullopt;
  const netsim::ScoreResult& r = *s.score;
  const size_t index = static_cast<size_t>(row) * r.grid.size() + knot;
  if (index >= r.compared.size() || !r.compared[index]) return std::nullopt;
  return r.residual[index].norm();
}

}  // namespace netlab::gui
