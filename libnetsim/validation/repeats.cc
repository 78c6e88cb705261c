#include "libnetsim/validation/repeats.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/errors.h"
#include "common/minimize.h"

namespace netlab::netsim {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string KnotText(const KnotTracks& tracks, int k) {
  std::string text =
      "(" + std::to_string(tracks.grid[k][0]) + "," + std::to_string(tracks.grid[k][1]) + ")";
  if (!tracks.net.empty()) text += " of net " + std::to_string(tracks.net[k]);
  return text;
}

// Sums of one spread row: sum |x - x_bar|^2 and sum (n - 1).
struct SpreadSums {
  double squares = 0.0, dof = 0.0;
  int points = 0;
  void Add(double s, int n) {
    squares += s;
    dof += n - 1;
    ++points;
  }
  void Finish(SpreadRow* row) const {
    row->points = points;
    row->rms_m = dof > 0 ? std::sqrt(squares / dof) : kNaN;
  }
};

// The trace of a measured knot-frame's covariance, m^2: its own, or 3 meas_sigma^2 without one.
double CovarianceTrace(const KnotTracks& meas, size_t i, double meas_sigma_m) {
  return meas.covariance.empty() ? 3 * meas_sigma_m * meas_sigma_m : meas.covariance[i].trace();
}

// Shot `shot`'s measured knot k at its measured time u, in the simulation's frame: linear between
// the two frames around u, both informative. False where there are none. `lost_variance`: how much
// less noise variance (trace, m^2) the interpolated point has than one measured frame at u,
// f (1 - f) tr(C_a + C_b) for weights 1 - f and f.
bool AlignedKnot(const KnotTracks& meas, const ScoreResult& shot, int k, double u,
                 double meas_sigma_m, Eigen::Vector3d* x, double* lost_variance) {
  const std::vector<double>& time = meas.time;
  const int knots = meas.knots();
  const double tol = 1e-9 * std::max(1.0, std::abs(u));
  if (time.empty() || u < time.front() - tol || u > time.back() + tol) return false;
  int j = static_cast<int>(std::upper_bound(time.begin(), time.end(), u) - time.begin()) - 1;
  j = std::clamp(j, 0, std::max(0, meas.frames() - 2));
  const int j1 = std::min(j + 1, meas.frames() - 1);
  const size_t a = static_cast<size_t>(j) * knots + k, b = static_cast<size_t>(j1) * knots + k;
  const double span = time[j1] - time[j];
  const double f = span > 0 ? std::clamp((u - time[j]) / span, 0.0, 1.0) : 0.0;
  // A frame of weight (nearly) zero need not be informative.
  const bool need_a = f < 1.0 - 1e-9;
  const bool need_b = f > 1e-9;
  const std::vector<uint8_t>& usable = shot.informative.empty() ? shot.compared : shot.informative;
  if ((need_a && !usable[a]) || (need_b && !usable[b])) return false;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  if (need_a) p += (1.0 - f) * meas.position[a];
  if (need_b) p += f * meas.position[b];
  *lost_variance =
      need_a && need_b
          ? f * (1.0 - f) *
                (CovarianceTrace(meas, a, meas_sigma_m) + CovarianceTrace(meas, b, meas_sigma_m))
          : 0.0;
  const ScoreSummary& s = shot.summary;
  *x = s.rotation.transpose() * (p - s.translation);
  return true;
}

// The RMS error over the shots' rows picked by `row_of`, each weighed by its informative points.
template <typename RowOf>
double PooledError(const std::vector<ScoreResult>& shots, RowOf row_of) {
  double e2 = 0.0;
  int n = 0;
  for (const ScoreResult& shot : shots) {
    const ScoreRow* row = row_of(shot.summary);
    if (!row) continue;
    const int informative = row->points - row->left_out;
    if (informative <= 0 || !std::isfinite(row->rms_m)) continue;
    e2 += row->rms_m * row->rms_m * informative;
    n += informative;
  }
  return n > 0 ? std::sqrt(e2 / n) : kNaN;
}

// The mean squared distance between shot i's knots and shot 0's at shot 0's informative frames,
// shot i read at simulated time s - tau_i (the noise variance its interpolation removed added
// back); NaN where they share fewer than 10 knot-frames.
double PairMeanSquare(const std::vector<const KnotTracks*>& measured,
                      const std::vector<ScoreResult>& shots, size_t i, double tau_i,
                      double meas_sigma_m) {
  const KnotTracks& ref = *measured[0];
  const double tau0 = shots[0].summary.time_offset_s;
  double sum = 0.0;
  int n = 0;
  for (int t = 0; t < ref.frames(); ++t)
    for (int k = 0; k < ref.knots(); ++k) {
      Eigen::Vector3d a, b;
      double lost_a = 0.0, lost_b = 0.0;
      if (!AlignedKnot(ref, shots[0], k, ref.time[t], meas_sigma_m, &a, &lost_a) ||
          !AlignedKnot(*measured[i], shots[i], k, ref.time[t] + tau0 - tau_i, meas_sigma_m, &b,
                       &lost_b))
        continue;
      // The noise the interpolation averaged away put back: without it a shot read between its
      // frames looks closer (0.09 ms of bias at 0.3 mm of noise in repeats_test).
      sum += (a - b).squaredNorm() + lost_a + lost_b;
      ++n;
    }
  return n >= 10 ? sum / n : kNaN;
}

// Each shot's time offset for the spread: shot 0's as its score fitted it; every other shot's
// moved to where it lies closest to shot 0 (a half-frame grid within 10 frames of its fitted
// offset, then golden-section search). A model's error that grows over the flight gives shots
// filmed over other stretches offsets apart by a share of it (0.9 ms on docs/score.md's repeats
// against the model without drag, 2.8 frames in repeats_test); the spread between the shots is
// theirs, not the model's. Offsets as fitted where the score does not fit time (the clocks are then
// trusted) or a shot shares no frames with shot 0.
std::vector<double> ShotsAlignedToEachOther(const std::vector<const KnotTracks*>& measured,
                                            const std::vector<ScoreResult>& shots,
                                            const ScoreOptions& options) {
  std::vector<double> tau;
  for (const ScoreResult& shot : shots) tau.push_back(shot.summary.time_offset_s);
  const KnotTracks& ref = *measured[0];
  if (!FitsTime(options.alignment) || ref.frames() < 2) return tau;
  const double frame = (ref.time.back() - ref.time.front()) / (ref.frames() - 1);
  for (size_t i = 1; i < shots.size(); ++i) {
    auto cost = [&](double x) {
      const double c = PairMeanSquare(measured, shots, i, x, options.meas_sigma_m);
      return std::isnan(c) ? std::numeric_limits<double>::infinity() : c;
    };
    if (std::isinf(cost(tau[i]))) continue;
    // A half-frame grid over 10 frames each side, then golden-section search around its best.
    double grid_best = tau[i], grid_cost = cost(tau[i]);
    for (int step = -20; step <= 20; ++step) {
      const double x = tau[i] + 0.5 * step * frame;
      const double c = cost(x);
      if (c < grid_cost) grid_best = x, grid_cost = c;
    }
    const double best =
        GoldenSection(cost, grid_best - 0.5 * frame, grid_best + 0.5 * frame, 1e-4 * frame);
    tau[i] = cost(best) <= grid_cost ? best : grid_best;
  }
  return tau;
}

}  // namespace

void CheckSameNet(const std::vector<const KnotTracks*>& measured,
                  const std::vector<std::string>& names) {
  if (measured.empty()) return;
  const KnotTracks& first = *measured[0];
  for (size_t i = 1; i < measured.size(); ++i) {
    const KnotTracks& other = *measured[i];
    const std::string what = names[i] + " is not a repeat of " + names[0] + ": ";
    if (other.knots() != first.knots())
      throw InputError(what + "it has " + std::to_string(other.knots()) + " knots, " + names[0] +
                       " " + std::to_string(first.knots()) +
                       " (/knots/grid): repeats of one case fly the same net");
    for (int k = 0; k < first.knots(); ++k) {
      const int net_a = first.net.empty() ? 0 : first.net[k];
      const int net_b = other.net.empty() ? 0 : other.net[k];
      if (other.grid[k] == first.grid[k] && net_a == net_b) continue;
      throw InputError(what + "its knot " + std::to_string(k) + " is " + KnotText(other, k) +
                       ", in " + names[0] + " " + KnotText(first, k) +
                       " (/knots/grid): repeats of one case fly the same net");
    }
  }
}

RepeatsSummary PoolRepeats(const std::vector<const KnotTracks*>& measured,
                           const std::vector<std::string>& names,
                           const std::vector<ScoreResult>& shots, const ScoreOptions& options) {
  RepeatsSummary r;
  r.names = names;
  // The pooled test: Fisher's combination of the shots' own tests. Under "the simulation is
  // right" the shots' p-values are independent and uniform, and F = -2 sum ln p_i ~ chi^2(2 S).
  // (The shots' scaled chi^2 summed instead weighs each by its correlation inflation: a shot
  // whose errors run through the flight, c ~ 70, counts little beside one of uncorrelated noise,
  // c ~ 2, whose covariances are too large, and the second's deficit of d2 hid the first's
  // excess.) Each shot's p at its sum d2 scaled by lambda: P(chi^2(nu_i / c_i) >= lambda X_i).
  double d2 = 0.0, x = 0.0, nu_eff = 0.0, e2 = 0.0;
  int informative = 0;
  std::vector<std::pair<double, double>> scaled;  // (nu_i / c_i, X_i) per shot
  for (const ScoreResult& shot : shots) {
    const ScoreSummary& s = shot.summary;
    const double inflation = s.tau_int * s.design_effect;
    const double sum = s.mean_d2 * s.points;
    r.points += s.points;
    r.dof += s.dof;
    r.effective_points += s.points / inflation;
    d2 += sum;
    x += sum / inflation;
    nu_eff += s.dof / inflation;
    scaled.emplace_back(s.dof / inflation, sum / inflation);
    const int n = s.points - s.left_out;
    if (n > 0 && std::isfinite(s.rms_m)) {
      e2 += s.rms_m * s.rms_m * n;
      informative += n;
    }
  }
  const auto fisher_p = [&](double lambda) {
    double f = 0.0;
    for (const auto& [nu, xi] : scaled)
      f -= 2.0 * std::log(std::max(UpperGammaQ(nu / 2, lambda * xi / 2), 1e-300));
    return UpperGammaQ(static_cast<double>(scaled.size()), f / 2);
  };
  r.rms_m = informative > 0 ? std::sqrt(e2 / informative) : kNaN;
  r.mean_d2 = r.points > 0 ? d2 / r.points : kNaN;
  r.scaled_d2 = x;
  r.effective_dof = nu_eff;
  r.p_value = fisher_p(1.0);
  // The pooled mean d2 at which the combined p reaches the significance, every shot's sum d2
  // scaled alike (p falls as the scale grows): bisection on the scale's logarithm.
  if (x > 0) {
    double lo = 1e-6, hi = 1e6;
    if (fisher_p(hi) >= options.significance || fisher_p(lo) < options.significance) {
      r.critical_mean_d2 = kNaN;
    } else {
      for (int i = 0; i < 200 && hi / lo > 1 + 1e-12; ++i) {
        const double mid = std::sqrt(lo * hi);
        (fisher_p(mid) >= options.significance ? lo : hi) = mid;
      }
      r.critical_mean_d2 = std::sqrt(lo * hi) * r.mean_d2;
    }
  } else {
    r.critical_mean_d2 = kNaN;
  }
  r.margin = r.critical_mean_d2 - r.mean_d2;
  r.verdict = r.p_value >= options.significance ? Verdict::kConsistent : Verdict::kInconsistent;

  // The spread between the shots at the first shot's frames, on the simulation's clock.
  const KnotTracks& ref = *measured[0];
  const ScoreResult& first = shots[0];
  const double tau0 = first.summary.time_offset_s;
  const std::vector<double> tau = ShotsAlignedToEachOther(measured, shots, options);
  for (double t : tau) r.spread_time_offset_s.push_back(t - tau0);
  const int knots = ref.knots();
  SpreadSums all, per_class[3];
  std::vector<SpreadSums> per_phase(first.summary.per_phase.size());
  std::vector<Eigen::Vector3d> xs;
  for (int t = 0; t < ref.frames(); ++t) {
    const double s = ref.time[t] + tau0;
    for (int k = 0; k < knots; ++k) {
      xs.clear();
      double lost = 0.0;
      for (size_t i = 0; i < shots.size(); ++i) {
        Eigen::Vector3d p;
        double lost_i = 0.0;
        if (!AlignedKnot(*measured[i], shots[i], k, s - tau[i], options.meas_sigma_m, &p, &lost_i))
          continue;
        xs.push_back(p);
        lost += lost_i;
      }
      const int n = static_cast<int>(xs.size());
      if (n < 2) continue;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const Eigen::Vector3d& p : xs) mean += p;
      mean /= n;
      // Independent points of noise variances v_i give E sum |x - x_bar|^2 = (n - 1) / n sum v_i:
      // the noise the interpolation averaged away is put back so.
      double squares = (n - 1.0) / n * lost;
      for (const Eigen::Vector3d& p : xs) squares += (p - mean).squaredNorm();
      all.Add(squares, n);
      per_class[first.knot_class[k]].Add(squares, n);
      for (size_t p = 0; p < per_phase.size(); ++p) {
        const ScoreRow& phase = first.summary.per_phase[p];
        if (ref.time[t] >= phase.start_s && ref.time[t] < phase.end_s) per_phase[p].Add(squares, n);
      }
    }
  }
  r.spread.name = "all";
  all.Finish(&r.spread);
  r.spread.error_rms_m = r.rms_m;
  for (int c = 0; c < 3; ++c) {
    r.spread_per_class[c].name = kKnotClassNames[c];
    per_class[c].Finish(&r.spread_per_class[c]);
    r.spread_per_class[c].error_rms_m =
        PooledError(shots, [c](const ScoreSummary& s) { return &s.per_class[c]; });
  }
  for (size_t p = 0; p < per_phase.size(); ++p) {
    SpreadRow row;
    row.name = first.summary.per_phase[p].name;
    row.start_s = first.summary.per_phase[p].start_s + tau0;
    row.end_s = first.summary.per_phase[p].end_s + tau0;
    per_phase[p].Finish(&row);
    row.error_rms_m = PooledError(shots, [p](const ScoreSummary& s) {
      return p < s.per_phase.size() ? &s.per_phase[p] : nullptr;
    });
    r.spread_per_phase.push_back(row);
  }
  return r;
}

RepeatsResult ScoreRepeats(const std::vector<const KnotTracks*>& measured,
                           const std::vector<std::string>& names, const KnotTracks& sim,
                           const ScoreOptions& options, const std::string& sim_name) {
  CheckSameNet(measured, names);
  RepeatsResult result;
  for (size_t i = 0; i < measured.size(); ++i)
    result.shots.push_back(Score(*measured[i], sim, options, names[i], sim_name));
  result.summary = PoolRepeats(measured, names, result.shots, options);
  result.combined = result.shots[0];
  ScoreSummary& c = result.combined.summary;
  const RepeatsSummary& r = result.summary;
  c.mean_d2 = r.mean_d2;
  c.dof = r.dof;
  c.effective_points = r.effective_points;
  c.p_value = r.p_value;
  c.critical_mean_d2 = r.critical_mean_d2;
  c.margin = r.margin;
  c.verdict = r.verdict;
  c.covariance_too_large =
      1 - UpperGammaQ(r.effective_dof / 2, r.scaled_d2 / 2) < options.significance;
  return result;
}

}  // namespace netlab::netsim
