#include "libnetsim/validation/score.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "common/hdf5_util.h"
#include "libnetsim/validation/alignment.h"
#include "libnetsim/validation/summary_fields.h"

namespace netlab::netsim {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Matrix7d = Eigen::Matrix<double, 7, 7>;
using Vector7d = Eigen::Matrix<double, 7, 1>;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

[[noreturn]] void Fail(const std::string& what) { throw std::invalid_argument(what); }

std::string KnotName(const std::array<int, 2>& g) {
  std::string name = "(";  // appended, not "(" + ...: GCC 12 warns of a false -Wrestrict
  name += std::to_string(g[0]);
  name += ",";
  name += std::to_string(g[1]);
  return name + ")";
}

// "frame 12 (t = 0.0670 s)": the frame number when the file has one, else the row.
std::string FrameName(const KnotTracks& tracks, int row) {
  std::ostringstream s;
  s << "frame " << (tracks.frame_index.empty() ? row : tracks.frame_index[row])
    << " (t = " << tracks.time[row] << " s)";
  return s.str();
}

using Point = ComparedPoint;

struct Fit {
  double tau = 0.0;
  Matrix3d rotation = Matrix3d::Identity();
  Vector3d translation = Vector3d::Zero();
};

// The evaluation of every point under one fit.
struct Evaluation {
  double cost = 0.0;  // sum d2
  int used = 0;
  Matrix7d normal = Matrix7d::Zero();    // J^T W J, parameters (tau, dtheta, dt)
  Vector7d gradient = Vector7d::Zero();  // J^T W r
};

class Scorer {
 public:
  Scorer(const KnotTracks& meas, const KnotTracks& sim, const std::vector<int>& sim_knot,
         std::vector<Point> points, const ScoreOptions& options)
      : meas_(meas),
        sim_(sim),
        interp_(sim, sim_knot),
        sim_knot_(sim_knot),
        points_(std::move(points)),
        options_(options) {}

  // Sigma_sim of knot k at simulated time t, simulation frame (zero, isotropic or the file's).
  Matrix3d SimCovariance(double t, int k) const {
    if (!sim_.covariance.empty()) {
      const auto& s = sim_.time;
      const int i =
          std::clamp(static_cast<int>(std::lower_bound(s.begin(), s.end(), t) - s.begin()), 0,
                     static_cast<int>(s.size()) - 1);
      return sim_.covariance[static_cast<size_t>(i) * sim_.knots() + sim_knot_[k]];
    }
    return Matrix3d::Identity() * options_.sim_sigma_m * options_.sim_sigma_m;
  }

  // Residual, weight and Jacobian of one point; false when the simulation is not available.
  bool Residual(const Point& pt, const Fit& fit, Vector3d* r, Matrix3d* w,
                Eigen::Matrix<double, 3, 7>* jacobian, double* interp_error = nullptr,
                Vector3d* sim_in_meas = nullptr) const {
    const double t = meas_.time[pt.frame] + fit.tau;
    Vector3d p, v;
    double error = 0.0;
    if (!interp_.At(t, pt.knot, &p, &v, &error)) return false;
    const Vector3d a = fit.rotation * p + fit.translation;
    *r = meas_.Position(pt.frame, pt.knot) - a;
    const Matrix3d cov = pt.meas_cov +
                         fit.rotation * SimCovariance(t, pt.knot) * fit.rotation.transpose() +
                         Matrix3d::Identity() * error * error;
    // Through the Cholesky factor: W = L^-T L^-1 stays symmetric positive definite for the
    // ill-conditioned covariances of two-camera points (a plain inverse gave negative d2 there).
    const Eigen::LLT<Matrix3d> llt(cov);
    const Matrix3d l_inv = llt.matrixL().solve(Matrix3d::Identity());
    *w = l_inv.transpose() * l_inv;
    if (jacobian) {
      jacobian->col(0) = -(fit.rotation * v);
      jacobian->block<3, 3>(0, 1) = Skew(a);
      jacobian->block<3, 3>(0, 4) = -Matrix3d::Identity();
    }
    if (interp_error) *interp_error = error;
    if (sim_in_meas) *sim_in_meas = a;
    return true;
  }

  // Sum d2 (and the normal equations when asked) over every `stride`-th point.
  Evaluation Evaluate(const Fit& fit, bool normal, int stride = 1) const {
    Evaluation e;
    Vector3d r;
    Matrix3d w;
    Eigen::Matrix<double, 3, 7> j;
    for (size_t i = 0; i < points_.size(); i += stride) {
      if (!active_.empty() && !active_[i]) continue;
      if (!Residual(points_[i], fit, &r, &w, normal ? &j : nullptr)) continue;
      e.cost += r.dot(w * r);
      ++e.used;
      if (normal) {
        const Eigen::Matrix<double, 7, 3> jtw = j.transpose() * w;
        e.normal.noalias() += jtw * j;
        e.gradient.noalias() += jtw * r;
      }
    }
    return e;
  }

  // Least-squares rigid motion meas_from_sim (Umeyama's, without scale) at offset tau, over
  // every stride-th point.
  bool Kabsch(Fit* fit, int stride) const {
    std::vector<Vector3d> a, b;
    for (size_t i = 0; i < points_.size(); i += stride) {
      Vector3d p;
      if (!interp_.At(meas_.time[points_[i].frame] + fit->tau, points_[i].knot, &p, nullptr,
                      nullptr))
        continue;
      a.push_back(p);
      b.push_back(meas_.Position(points_[i].frame, points_[i].knot));
    }
    if (a.size() < 3) return false;
    Eigen::Matrix3Xd from(3, a.size()), to(3, b.size());
    for (size_t i = 0; i < a.size(); ++i) from.col(i) = a[i], to.col(i) = b[i];
    const Eigen::Matrix4d m = Eigen::umeyama(from, to, /*with_scaling=*/false);
    fit->rotation = m.topLeftCorner<3, 3>();
    fit->translation = m.topRightCorner<3, 1>();
    return true;
  }

  const std::vector<Point>& points() const { return points_; }
  const SimInterpolant& interpolant() const { return interp_; }

  // Restricts Evaluate to the points simulated at every offset within tau +- margin, so that the
  // refinement compares costs over one set of points.
  void FixPointSet(double tau, double margin) {
    active_.assign(points_.size(), 0);
    Vector3d p;
    for (size_t i = 0; i < points_.size(); ++i) {
      const double t = meas_.time[points_[i].frame];
      active_[i] = interp_.At(t + tau - margin, points_[i].knot, &p, nullptr, nullptr) &&
                   interp_.At(t + tau + margin, points_[i].knot, &p, nullptr, nullptr);
    }
  }

 private:
  const KnotTracks& meas_;
  const KnotTracks& sim_;
  SimInterpolant interp_;
  const std::vector<int>& sim_knot_;
  std::vector<Point> points_;
  std::vector<uint8_t> active_;  // empty: every point
  const ScoreOptions& options_;
};

// The measured time span must overlap the simulation's by half at offset tau.
bool EnoughOverlap(const KnotTracks& meas, const SimInterpolant& interp, double tau) {
  const double lo = std::max(meas.time.front() + tau, interp.begin());
  const double hi = std::min(meas.time.back() + tau, interp.end());
  const double span = meas.time.back() - meas.time.front();
  return hi > lo && (span <= 0 || hi - lo >= 0.5 * span);
}

// Integrated autocorrelation time of the d2 series (frames), pooled over knots, each series
// centred on its own mean; Sokal's automatic window (the smallest W with W >= 5 tau(W)).
double IntegratedAutocorrelation(const std::vector<double>& x, int frames, int knots) {
  std::vector<double> centred(x.size(), kNaN);
  for (int k = 0; k < knots; ++k) {
    double sum = 0;
    int n = 0;
    for (int t = 0; t < frames; ++t)
      if (std::isfinite(x[static_cast<size_t>(t) * knots + k])) sum += x[t * knots + k], ++n;
    if (n < 2) continue;
    for (int t = 0; t < frames; ++t) {
      const size_t i = static_cast<size_t>(t) * knots + k;
      if (std::isfinite(x[i])) centred[i] = x[i] - sum / n;
    }
  }
  auto autocov = [&](int lag) {
    double sum = 0;
    long n = 0;
    for (int t = 0; t + lag < frames; ++t)
      for (int k = 0; k < knots; ++k) {
        const double a = centred[static_cast<size_t>(t) * knots + k];
        const double b = centred[static_cast<size_t>(t + lag) * knots + k];
        if (std::isfinite(a) && std::isfinite(b)) sum += a * b, ++n;
      }
    return n > 0 ? sum / n : 0.0;
  };
  const double c0 = autocov(0);
  if (!(c0 > 0)) return 1.0;
  double tau = 1.0;
  for (int lag = 1; lag < frames / 2; ++lag) {
    tau += 2.0 * autocov(lag) / c0;
    if (lag >= 5.0 * tau) break;
  }
  return std::max(1.0, tau);
}

// Within-frame inflation: var(sum over a frame's knots) / sum of the knots' variances.
double DesignEffect(const std::vector<double>& x, int frames, int knots) {
  std::vector<double> mean(knots, 0.0);
  std::vector<int> count(knots, 0);
  for (int t = 0; t < frames; ++t)
    for (int k = 0; k < knots; ++k)
      if (std::isfinite(x[static_cast<size_t>(t) * knots + k]))
        mean[k] += x[t * knots + k], ++count[k];
  for (int k = 0; k < knots; ++k) mean[k] = count[k] ? mean[k] / count[k] : 0.0;
  double sum_sq_of_sums = 0, sum_of_sq = 0;
  for (int t = 0; t < frames; ++t) {
    double s = 0;
    for (int k = 0; k < knots; ++k) {
      const double v = x[static_cast<size_t>(t) * knots + k];
      if (!std::isfinite(v)) continue;
      s += v - mean[k];
      sum_of_sq += (v - mean[k]) * (v - mean[k]);
    }
    sum_sq_of_sums += s * s;
  }
  return sum_of_sq > 0 ? std::max(1.0, sum_sq_of_sums / sum_of_sq) : 1.0;
}

double QuadArea(const Vector3d c[4]) { return 0.5 * (c[2] - c[0]).cross(c[3] - c[1]).norm(); }

// A compared point into a row: d2 always, its error only when informative.
void AddRow(ScoreRow* row, double e2, double d2, bool informative) {
  row->points++;
  row->mean_d2 += d2;
  if (!informative) {
    row->left_out++;
    return;
  }
  row->rms_m += e2;  // sum of squares until Finish
  row->max_m = std::max(row->max_m, std::sqrt(e2));
}
void FinishRow(ScoreRow* row) {
  if (row->points == 0) {
    row->rms_m = row->mean_d2 = kNaN;
    return;
  }
  const int n = row->points - row->left_out;
  row->rms_m = n > 0 ? std::sqrt(row->rms_m / n) : kNaN;
  row->mean_d2 /= row->points;
}

}  // namespace

bool FitsTime(Alignment a) { return a == Alignment::kTime || a == Alignment::kTimeAndRigid; }
bool FitsRigid(Alignment a) { return a == Alignment::kRigid || a == Alignment::kTimeAndRigid; }

bool ParseAlignment(const std::string& text, Alignment* alignment) {
  static const std::map<std::string, Alignment> names = {{"none", Alignment::kNone},
                                                         {"time", Alignment::kTime},
                                                         {"rigid", Alignment::kRigid},
                                                         {"time+rigid", Alignment::kTimeAndRigid}};
  const auto it = names.find(text);
  if (it == names.end()) return false;
  *alignment = it->second;
  return true;
}

std::string AlignmentName(Alignment alignment) {
  switch (alignment) {
    case Alignment::kNone: return "none";
    case Alignment::kTime: return "time";
    case Alignment::kRigid: return "rigid";
    case Alignment::kTimeAndRigid: return "time+rigid";
  }
  return "?";
}

std::string VerdictName(Verdict verdict) {
  return verdict == Verdict::kConsistent ? "consistent" : "inconsistent";
}

std::string ContactFromName(ContactFrom from) {
  switch (from) {
    case ContactFrom::kNone: return "none";
    case ContactFrom::kGiven: return "given";
    case ContactFrom::kSimulation: return "simulation";
  }
  return "?";
}

bool ScoreOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& what) {
    if (error) *error = what;
    return false;
  };
  if (!std::isfinite(time_offset_s)) return fail("time_offset_s must be finite");
  if (!(max_time_offset_s >= 0) || !std::isfinite(max_time_offset_s))
    return fail("max_time_offset_s must be >= 0");
  if (!(sim_sigma_m >= 0) || !std::isfinite(sim_sigma_m)) return fail("sim_sigma_m must be >= 0");
  if (!(meas_sigma_m >= 0) || !std::isfinite(meas_sigma_m))
    return fail("meas_sigma_m must be >= 0");
  if (!(significance > 0 && significance < 1)) return fail("significance must be in (0, 1)");
  if (!(max_interpolation_fraction > 0)) return fail("max_interpolation_fraction must be > 0");
  return true;
}

// Q(a, x) by its series (x < a + 1) or continued fraction (Numerical Recipes 6.2); for the very
// large a of long recordings (nu/2 > 1e5) the Wilson-Hilferty normal approximation of chi^2,
// accurate there to ~1e-4 absolute.
double UpperGammaQ(double a, double x) {
  if (x <= 0) return 1.0;
  if (a > 1e5) {
    const double nu = 2 * a, chi2 = 2 * x;
    const double z = (std::cbrt(chi2 / nu) - (1 - 2 / (9 * nu))) / std::sqrt(2 / (9 * nu));
    return 0.5 * std::erfc(z / std::sqrt(2.0));
  }
  const double log_prefactor = -x + a * std::log(x) - std::lgamma(a);
  if (x < a + 1) {
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 100000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-15) break;
    }
    return std::clamp(1.0 - sum * std::exp(log_prefactor), 0.0, 1.0);
  }
  constexpr double kTiny = 1e-300;
  double b = x + 1 - a, c = 1 / kTiny, d = 1 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    const double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1) < 1e-15) break;
  }
  return std::clamp(std::exp(log_prefactor) * h, 0.0, 1.0);
}

double Chi2Quantile(double p, double nu) {
  double lo = 0, hi = std::max(10.0, nu + 20 * std::sqrt(2 * nu) + 50);
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (1 - UpperGammaQ(nu / 2, mid / 2) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

namespace {

// The inputs of one Score() call, as its stages read them.
struct ScoreInput {
  const KnotTracks& meas;
  const KnotTracks& sim;
  const ScoreOptions& options;
  const std::string& meas_name;
  const std::string& sim_name;
};

// The options, and the files' own shapes and time axes.
void CheckInput(const ScoreInput& in) {
  const KnotTracks &meas = in.meas, &sim = in.sim;
  std::string why;
  if (!in.options.IsValid(&why)) Fail("score options: " + why);
  // The files' own shapes (the reader checks them; tracks built in memory may not be).
  for (const auto& [tracks, name] :
       {std::pair(&meas, in.meas_name), std::pair(&sim, in.sim_name)}) {
    try {
      tracks->CheckConsistent();
    } catch (const std::invalid_argument& e) {
      Fail(name + ": " + e.what());
    }
    if (tracks->knots() == 0) Fail(name + ": /knots/grid has no knot");
    for (int t = 0; t < tracks->frames(); ++t) {
      if (!std::isfinite(tracks->time[t]))
        Fail(name + ": /time[" + std::to_string(t) + "] is not a number");
      if (t > 0 && !(tracks->time[t] > tracks->time[t - 1]))
        Fail(name + ": /time is not increasing at row " + std::to_string(t) + " (" +
             std::to_string(tracks->time[t - 1]) + " s then " + std::to_string(tracks->time[t]) +
             " s)");
    }
  }
  if (sim.frames() < 4)
    Fail(in.sim_name + ": " + std::to_string(sim.frames()) +
         " frames; cubic interpolation in time needs at least 4");
  if (meas.frames() < 1) Fail(in.meas_name + ": no frame");
}

// The same net in both: every knot (net, row, col) of one has its counterpart in the other.
// Returns the simulation's index of each measured knot.
std::vector<int> MatchKnots(const ScoreInput& in) {
  const KnotTracks &meas = in.meas, &sim = in.sim;
  const std::string &meas_name = in.meas_name, &sim_name = in.sim_name;
  const int knots = meas.knots();
  std::vector<int> sim_knot(knots);
  for (int k = 0; k < knots; ++k) {
    sim_knot[k] =
        sim.FindKnot(meas.grid[k][0], meas.grid[k][1], meas.net.empty() ? 0 : meas.net[k]);
    if (sim_knot[k] < 0)
      Fail("grid mismatch: knot " + KnotName(meas.grid[k]) + " of " + meas_name +
           " (/knots/grid row " + std::to_string(k) + ") is not in " + sim_name + " (" +
           std::to_string(sim.knots()) + " knots there, " + std::to_string(knots) + " here)");
  }
  if (sim.knots() != knots)
    Fail("grid mismatch: " + sim_name + " has " + std::to_string(sim.knots()) + " knots, " +
         meas_name + " " + std::to_string(knots) + ": not the same net");
  return sim_knot;
}

// NaN in the simulation is a blow-up carried on: stop, naming it. Only the valid knot-frames
// count: a simulation given as tracks (a triangulated file, or one with knots lost) holds NaN
// where /knots/valid is 0, and those are never read.
void CheckSimulationFinite(const ScoreInput& in) {
  const KnotTracks& sim = in.sim;
  const int knots = in.meas.knots();  // the simulation's too (MatchKnots)
  for (int t = 0; t < sim.frames(); ++t)
    for (int k = 0; k < knots; ++k) {
      if (!sim.Valid(t, k)) continue;
      if (!sim.Position(t, k).allFinite())
        Fail(in.sim_name + ": /knots/position is not a number at " + FrameName(sim, t) + ", knot " +
             KnotName(sim.grid[k]));
      if (!sim.covariance.empty() &&
          !sim.covariance[static_cast<size_t>(t) * knots + k].allFinite())
        Fail(in.sim_name + ": /knots/covariance is not a number at " + FrameName(sim, t) +
             ", knot " + KnotName(sim.grid[k]) + ", where /knots/valid is 1");
    }
}

// Sigma_meas of knot k in frame t (`where`, for the message): the file's, checked symmetric
// positive definite, else the isotropic meas_sigma_m.
Matrix3d MeasuredCovariance(const ScoreInput& in, int t, int k, const std::string& where) {
  const KnotTracks& meas = in.meas;
  if (meas.covariance.empty())
    return Matrix3d::Identity() * in.options.meas_sigma_m * in.options.meas_sigma_m;
  const Matrix3d cov = meas.covariance[static_cast<size_t>(t) * meas.knots() + k];
  if (!cov.allFinite()) Fail(in.meas_name + ": /knots/covariance is not a number at " + where);
  const double scale = cov.cwiseAbs().maxCoeff();
  const Eigen::LLT<Matrix3d> llt(cov);
  if ((cov - cov.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale || scale <= 0 ||
      llt.info() != Eigen::Success ||
      llt.matrixL().toDenseMatrix().diagonal().minCoeff() <= std::sqrt(scale) * 1e-9) {
    std::ostringstream s;
    s << in.meas_name << ": /knots/covariance is not symmetric positive definite at " << where
      << " (eigenvalues " << Eigen::SelfAdjointEigenSolver<Matrix3d>(cov).eigenvalues().transpose()
      << " m^2)";
    Fail(s.str());
  }
  return cov;
}

// The measured points, each with a checked covariance; the knot-frames not measured (valid = 0)
// are counted in `masked`.
std::vector<Point> MeasuredPoints(const ScoreInput& in, int* masked) {
  const KnotTracks& meas = in.meas;
  const std::string& meas_name = in.meas_name;
  if (meas.covariance.empty() && in.options.meas_sigma_m <= 0)
    Fail(meas_name +
         ": no /knots/covariance to weight the residuals by (give a measurement "
         "sigma, --meas-sigma)");
  std::vector<Point> points;
  for (int t = 0; t < meas.frames(); ++t)
    for (int k = 0; k < meas.knots(); ++k) {
      if (!meas.Valid(t, k)) {
        ++*masked;
        continue;
      }
      const std::string where = FrameName(meas, t) + ", knot " + KnotName(meas.grid[k]);
      if (!meas.Position(t, k).allFinite())
        Fail(meas_name + ": /knots/position is not a number at " + where +
             " (a missing knot must have /knots/valid = 0)");
      points.push_back({t, k, MeasuredCovariance(in, t, k, where)});
    }
  if (points.empty()) Fail(meas_name + ": no valid knot in any frame");
  return points;
}

// Time overlap at the starting offset (or anywhere in the search window): what to say when there
// is none.
std::string NoOverlapMessage(const ScoreInput& in) {
  const KnotTracks &meas = in.meas, &sim = in.sim;
  std::ostringstream o;
  // The spans overlap, but the simulation's knots are lost (/knots/valid 0) around every
  // measured knot-frame: say so, not "no overlap".
  const double tau = in.options.time_offset_s;
  const double lo = std::max(meas.time.front() + tau, sim.time.front());
  const double hi = std::min(meas.time.back() + tau, sim.time.back());
  const double span = meas.time.back() - meas.time.front();
  size_t valid = 0;
  for (uint8_t v : sim.valid) valid += v != 0;
  if (hi >= lo && (span <= 0 || hi - lo >= 0.5 * span) && valid < sim.valid.size()) {
    o << "no measured knot-frame can be compared: " << in.sim_name << " has "
      << sim.valid.size() - valid << " of its " << sim.valid.size()
      << " knot-frames lost (/knots/valid 0), and a knot is simulated at a time only where it "
      << "is valid in the 4 frames around that time and in 5 consecutive frames near them (for "
      << "its interpolation and the interpolation's error); give --sim a simulation (netlab "
      << "simulate), or tracks with fewer knots lost";
    return o.str();
  }
  o << "no overlap in time: " << in.meas_name << " spans " << meas.time.front() << " .. "
    << meas.time.back() << " s, " << in.sim_name << " " << sim.time.front() << " .. "
    << sim.time.back() << " s (offset " << in.options.time_offset_s << " s";
  if (FitsTime(in.options.alignment)) o << " +- " << in.options.max_time_offset_s << " s searched";
  o << "; at least half of the measured span must be simulated)";
  return o.str();
}

// The alignment asked for, and both files' sampling intervals.
void StartSummary(const ScoreInput& in, ScoreSummary* s) {
  const KnotTracks &meas = in.meas, &sim = in.sim;
  s->alignment = in.options.alignment;
  s->sim_interval_s = (sim.time.back() - sim.time.front()) / (sim.frames() - 1);
  s->meas_interval_s =
      meas.frames() > 1 ? (meas.time.back() - meas.time.front()) / (meas.frames() - 1) : 0.0;
}

// What stage 1 hands on: the fit, and the normal matrix of its free parameters there.
struct FittedAlignment {
  Fit fit;
  int parameters = 0;      // p: 1 for the time offset, 6 for the rigid motion
  Eigen::MatrixXd normal;  // J^T W J over the free parameters, p x p (empty when p = 0)
};

// The starting fit: with the time fitted, a coarse search over the window on a thinned set of
// points (with a rigid fit, the best rigid motion at each candidate); else the fixed offset.
Fit SearchTimeOffset(const ScoreInput& in, const ScoreSummary& s, const Scorer& scorer) {
  const KnotTracks& meas = in.meas;
  const ScoreOptions& options = in.options;
  const SimInterpolant& interp = scorer.interpolant();
  const bool fit_rigid = FitsRigid(options.alignment);
  const int stride = std::max<int>(1, static_cast<int>(scorer.points().size() / 20000));
  if (!FitsTime(options.alignment)) {
    Fit fit;
    fit.tau = options.time_offset_s;
    if (!EnoughOverlap(meas, interp, fit.tau)) Fail(NoOverlapMessage(in));
    if (fit_rigid && !scorer.Kabsch(&fit, stride)) Fail(NoOverlapMessage(in));
    return fit;
  }
  const double step = 0.5 * std::min(s.sim_interval_s,
                                     s.meas_interval_s > 0 ? s.meas_interval_s : s.sim_interval_s);
  const int steps = static_cast<int>(std::ceil(options.max_time_offset_s / step));
  double best = std::numeric_limits<double>::infinity();
  Fit best_fit;
  for (int j = -steps; j <= steps; ++j) {
    Fit candidate;
    candidate.tau = options.time_offset_s + j * step;
    if (!EnoughOverlap(meas, interp, candidate.tau)) continue;
    if (fit_rigid && !scorer.Kabsch(&candidate, stride)) continue;
    const Evaluation e = scorer.Evaluate(candidate, false, stride);
    if (e.used == 0) continue;
    if (e.cost / e.used < best) best = e.cost / e.used, best_fit = candidate;
  }
  if (!std::isfinite(best)) Fail(NoOverlapMessage(in));
  return best_fit;
}

// Gauss-Newton with step halving from *fit, over the `free` parameters (indices into (tau,
// dtheta, dt)); 7 parameters, normal equations summed over the points. Returns the normal matrix
// of the free parameters at the fit.
Eigen::MatrixXd RefineFit(const ScoreOptions& options, const std::vector<int>& free,
                          const Scorer& scorer, Fit* fit) {
  const int p = static_cast<int>(free.size());
  Evaluation e = scorer.Evaluate(*fit, true);
  for (int iteration = 0; iteration < 30; ++iteration) {
    Eigen::MatrixXd h(p, p);
    Eigen::VectorXd g(p);
    for (int a = 0; a < p; ++a) {
      g(a) = e.gradient(free[a]);
      for (int b = 0; b < p; ++b) h(a, b) = e.normal(free[a], free[b]);
    }
    const Eigen::VectorXd delta = -h.ldlt().solve(g);
    bool improved = false;
    for (double scale = 1.0; scale > 1e-4; scale *= 0.5) {
      Vector7d full = Vector7d::Zero();
      for (int a = 0; a < p; ++a) full(free[a]) = scale * delta(a);
      Fit trial = *fit;
      trial.tau += full(0);
      if (std::abs(trial.tau - options.time_offset_s) > options.max_time_offset_s) continue;
      trial.rotation = ExpSo3(full.segment<3>(1)) * fit->rotation;
      trial.translation = ExpSo3(full.segment<3>(1)) * fit->translation + full.segment<3>(4);
      const Evaluation te = scorer.Evaluate(trial, true);
      // The same points (the set is fixed; a step beyond its margin loses some) and no more cost.
      if (te.used == e.used && te.cost <= e.cost) {
        *fit = trial;
        const double change = e.cost - te.cost;
        e = te;
        improved = change > 1e-10 * std::max(1.0, e.cost);
        break;
      }
    }
    if (!improved) break;
  }
  Eigen::MatrixXd normal_free(p, p);
  for (int a = 0; a < p; ++a)
    for (int b = 0; b < p; ++b) normal_free(a, b) = e.normal(free[a], free[b]);
  return normal_free;
}

// Stage 1: the coarse search, then Gauss-Newton on every fitted parameter.
FittedAlignment FitAlignment(const ScoreInput& in, const ScoreSummary& s, Scorer* scorer) {
  const bool fit_time = FitsTime(in.options.alignment);
  FittedAlignment fitted;
  fitted.fit = SearchTimeOffset(in, s, *scorer);
  std::vector<int> free;  // indices into (tau, dtheta, dt)
  if (fit_time) free.push_back(0);
  if (FitsRigid(in.options.alignment))
    for (int i = 1; i < 7; ++i) free.push_back(i);
  fitted.parameters = static_cast<int>(free.size());
  if (fitted.parameters > 0) {
    scorer->FixPointSet(fitted.fit.tau, fit_time ? 2 * s.sim_interval_s : 0.0);
    fitted.normal = RefineFit(in.options, free, *scorer, &fitted.fit);
  }
  return fitted;
}

// Sums over the compared knot-frames that stage 3 turns into the summary's numbers (errors in
// m over the informative points; d2 over all).
struct ResidualSums {
  double weighted_e2 = 0, weights = 0;      // sum w |r|^2, sum w (w = 3 / trace of the covariance)
  double d2 = 0, e2 = 0;                    // sum d2, sum |r|^2
  double interp_sq = 0, meas_var = 0;       // sum sigma_interp^2, sum trace(Sigma_meas) / 3
  double baseline_d2 = 0, baseline_e2 = 0;  // the straight-line flight's sum d2, sum |r|^2
  int baseline_points = 0;
};

// r and d2 of every measured point at the fit ([T*K], NaN where not compared), and the
// simulated positions in the measured frame. A point the simulation does not reach is masked.
void ResidualsAtFit(const KnotTracks& meas, const Scorer& scorer, const Fit& fit,
                    ScoreResult* result, std::vector<Vector3d>* sim_pos, ResidualSums* sums,
                    std::vector<double>* sigma) {
  result->time = meas.time;
  result->grid = meas.grid;
  const size_t cells = static_cast<size_t>(meas.frames()) * meas.knots();
  result->residual.assign(cells, Vector3d::Constant(kNaN));
  result->d2.assign(cells, kNaN);
  result->compared.assign(cells, 0);
  result->sim_var.assign(cells, kNaN);
  result->meas_var.assign(cells, kNaN);
  sigma->assign(cells, kNaN);
  sim_pos->assign(cells, Vector3d::Constant(kNaN));
  for (const Point& pt : scorer.points()) {
    Vector3d r, a;
    Matrix3d w;
    double error;
    if (!scorer.Residual(pt, fit, &r, &w, nullptr, &error, &a)) {
      ++result->summary.masked;
      continue;
    }
    const size_t i = static_cast<size_t>(pt.frame) * meas.knots() + pt.knot;
    // Every number read is checked finite; a NaN here would be a bug, and would index the d2
    // histogram out of its bins (the crash a triangulated file given as --sim once caused).
    if (!std::isfinite(r.dot(w * r)))
      throw std::logic_error("score: d2 is not a number at " + FrameName(meas, pt.frame) +
                             ", knot " + KnotName(meas.grid[pt.knot]));
    result->residual[i] = r;
    result->d2[i] = r.dot(w * r);
    result->compared[i] = 1;
    result->sim_var[i] = scorer.SimCovariance(meas.time[pt.frame] + fit.tau, pt.knot).trace();
    result->meas_var[i] = pt.meas_cov.trace();
    (*sim_pos)[i] = a;
    (*sigma)[i] = std::sqrt(
        std::max(0.0, Eigen::SelfAdjointEigenSolver<Matrix3d>(pt.meas_cov, Eigen::EigenvaluesOnly)
                          .eigenvalues()[2]));
    const double weight = 3.0 / w.inverse().trace();
    sums->weighted_e2 += weight * r.squaredNorm();
    sums->weights += weight;
    sums->interp_sq += error * error;
    sums->meas_var += pt.meas_cov.trace() / 3;
  }
}

// The informative points: compared, with their largest sigma within the bound (given, or a
// multiple of the median over the compared points); the bound, the count left out and the
// spread of the informative sigmas into the summary.
void MarkInformative(const ScoreOptions& options, const std::vector<double>& sigma,
                     ScoreResult* result) {
  ScoreSummary& s = result->summary;
  result->informative.assign(result->compared.size(), 0);
  std::vector<double> all;
  for (size_t i = 0; i < sigma.size(); ++i)
    if (result->compared[i]) all.push_back(sigma[i]);
  if (all.empty()) return;
  std::sort(all.begin(), all.end());
  s.median_sigma_m = all[all.size() / 2];
  std::ostringstream from;
  if (options.max_sigma_m > 0) {
    s.sigma_bound_m = options.max_sigma_m;
    from << "given";
  } else {
    s.sigma_bound_m = options.informative_sigma_factor * s.median_sigma_m;
    from.precision(3);
    from << options.informative_sigma_factor << " x the median sigma (" << s.median_sigma_m * 1e3
         << " mm)";
  }
  s.sigma_bound_from = from.str();
  std::vector<double> kept;
  for (size_t i = 0; i < sigma.size(); ++i) {
    if (!result->compared[i]) continue;
    if (sigma[i] <= s.sigma_bound_m) {
      result->informative[i] = 1;
      kept.push_back(sigma[i]);
      continue;
    }
    ++s.left_out;
    s.left_out_max_sigma_m = std::max(s.left_out_max_sigma_m, sigma[i]);
    s.left_out_max_error_m = std::max(s.left_out_max_error_m, result->residual[i].norm());
  }
  if (kept.size() >= 2) {
    std::sort(kept.begin(), kept.end());
    const double p10 = kept[kept.size() / 10], p90 = kept[kept.size() * 9 / 10];
    s.sigma_spread = p10 > 0 ? p90 / p10 : kNaN;
  }
}

// Each net's grid extent: its largest row and column.
std::map<int, std::array<int, 2>> NetExtents(const KnotTracks& meas) {
  std::map<int, std::array<int, 2>> extent;
  for (int k = 0; k < meas.knots(); ++k) {
    auto& e = extent[meas.net.empty() ? 0 : meas.net[k]];
    e[0] = std::max(e[0], meas.grid[k][0]);
    e[1] = std::max(e[1], meas.grid[k][1]);
  }
  return extent;
}

// The knots' classes, from each net's grid extent.
std::vector<int> KnotClasses(const KnotTracks& meas,
                             const std::map<int, std::array<int, 2>>& extent) {
  std::vector<int> knot_class(meas.knots());
  for (int k = 0; k < meas.knots(); ++k) {
    const auto& e = extent.at(meas.net.empty() ? 0 : meas.net[k]);
    const bool row_edge = meas.grid[k][0] == 0 || meas.grid[k][0] == e[0];
    const bool col_edge = meas.grid[k][1] == 0 || meas.grid[k][1] == e[1];
    knot_class[k] = static_cast<int>(row_edge && col_edge   ? KnotClass::kCorner
                                     : row_edge || col_edge ? KnotClass::kEdge
                                                            : KnotClass::kInner);
  }
  return knot_class;
}

// The first measured frame with a compared knot; the number of frames when there is none.
int FirstComparedFrame(const ScoreResult& result, int frames, int knots) {
  int first_frame = frames;
  for (int t = 0; t < frames && first_frame == frames; ++t)
    for (int k = 0; k < knots; ++k)
      if (result.compared[static_cast<size_t>(t) * knots + k]) first_frame = t;
  return first_frame;
}

// Skill baseline: straight-line flight of every knot from its simulated state at the first
// compared time (simulated time t0), seen in the measured frame through the fit.
class StraightLineFlight {
 public:
  StraightLineFlight(const SimInterpolant& interp, const Fit& fit, double t0, int knots)
      : fit_(fit), t0_(t0), p0_(knots), v0_(knots), has0_(knots) {
    for (int k = 0; k < knots; ++k) has0_[k] = interp.At(t0, k, &p0_[k], &v0_[k], nullptr);
  }

  // False when the simulation has no state of knot k at t0.
  bool Covers(int k) const { return has0_[k]; }

  // Knot k at measured time t_meas, measured frame.
  Vector3d At(int k, double t_meas) const {
    const double ts = t_meas + fit_.tau;
    return fit_.rotation * (p0_[k] + v0_[k] * (ts - t0_)) + fit_.translation;
  }

 private:
  const Fit& fit_;
  double t0_;
  std::vector<Vector3d> p0_, v0_;
  std::vector<bool> has0_;
};

// The corners of the first net (row-major order around the polygon).
std::array<int, 4> FirstNetCorners(const KnotTracks& meas,
                                   const std::map<int, std::array<int, 2>>& extent) {
  const auto& e0 = extent.at(meas.net.empty() ? 0 : meas.net[0]);
  const int net0 = meas.net.empty() ? 0 : meas.net[0];
  return {meas.FindKnot(0, 0, net0), meas.FindKnot(0, e0[1], net0),
          meas.FindKnot(e0[0], e0[1], net0), meas.FindKnot(e0[0], 0, net0)};
}

// The net's side: the thread length along the first net's first row in the first simulated
// frame (each link in the first frame that has both its knots valid; a simulation's are all).
double FirstRowLength(const KnotTracks& meas, const KnotTracks& sim,
                      const std::vector<int>& sim_knot,
                      const std::map<int, std::array<int, 2>>& extent) {
  const auto& e0 = extent.at(meas.net.empty() ? 0 : meas.net[0]);
  const int net0 = meas.net.empty() ? 0 : meas.net[0];
  double side = 0.0;
  for (int c = 0; c < e0[1]; ++c) {
    const int a = meas.FindKnot(0, c, net0), b = meas.FindKnot(0, c + 1, net0);
    if (a < 0 || b < 0) continue;
    for (int t = 0; t < sim.frames(); ++t)
      if (sim.Valid(t, sim_knot[a]) && sim.Valid(t, sim_knot[b])) {
        side += (sim.Position(t, sim_knot[b]) - sim.Position(t, sim_knot[a])).norm();
        break;
      }
  }
  return side;
}

// The tables' rows named and emptied, the per-frame series NaN until filled.
void StartTables(const KnotTracks& meas, ScoreResult* result) {
  ScoreSummary& s = result->summary;
  const int frames = meas.frames(), knots = meas.knots();
  for (auto& row : s.per_class) row = ScoreRow{};
  for (int c = 0; c < 3; ++c) s.per_class[c].name = kKnotClassNames[c];
  s.per_knot.resize(knots);
  for (int k = 0; k < knots; ++k) s.per_knot[k].name = KnotName(meas.grid[k]);
  result->rms_per_class.assign(frames, {kNaN, kNaN, kNaN});
  result->area_measured.assign(frames, kNaN);
  result->area_simulated.assign(frames, kNaN);
  result->centroid_measured.assign(frames, Vector3d::Constant(kNaN));
  result->centroid_simulated.assign(frames, Vector3d::Constant(kNaN));
  result->corner_distance_measured.assign(frames, {kNaN, kNaN, kNaN, kNaN, kNaN, kNaN});
  result->corner_distance_simulated = result->corner_distance_measured;
}

// Frame t's compared knots into the sums, the per-knot and per-class rows, the frame's RMS per
// class and its centroids; and the baseline's error there.
void TabulateFrame(int t, const KnotTracks& meas, const std::vector<Vector3d>& sim_pos,
                   const StraightLineFlight& baseline, ScoreResult* result, ResidualSums* sums) {
  ScoreSummary& s = result->summary;
  const int knots = meas.knots();
  std::array<double, 3> class_sq = {0, 0, 0};
  std::array<int, 3> class_n = {0, 0, 0};
  Vector3d cm = Vector3d::Zero(), cs = Vector3d::Zero();
  int n = 0;
  for (int k = 0; k < knots; ++k) {
    const size_t i = static_cast<size_t>(t) * knots + k;
    if (!result->compared[i]) continue;
    const double e2 = result->residual[i].squaredNorm();
    const int knot_class = result->knot_class[k];
    const bool informative = result->informative[i] != 0;
    sums->d2 += result->d2[i];
    AddRow(&s.per_knot[k], e2, result->d2[i], informative);
    AddRow(&s.per_class[knot_class], e2, result->d2[i], informative);
    if (!informative) continue;  // its error in m says nothing: d2 only
    sums->e2 += e2;
    s.max_m = std::max(s.max_m, std::sqrt(e2));
    class_sq[knot_class] += e2;
    class_n[knot_class]++;
    cm += meas.Position(t, k);
    cs += sim_pos[i];
    ++n;
    if (baseline.Covers(k)) {
      const Vector3d rb = meas.Position(t, k) - baseline.At(k, meas.time[t]);
      sums->baseline_e2 += rb.squaredNorm();
      ++sums->baseline_points;
    }
  }
  for (int c = 0; c < 3; ++c)
    if (class_n[c]) result->rms_per_class[t][c] = std::sqrt(class_sq[c] / class_n[c]);
  if (n > 0) {
    result->centroid_measured[t] = cm / n;
    result->centroid_simulated[t] = cs / n;
  }
}

// Frame t's corner polygon and corner distances (01 12 23 30 02 13), measured and simulated.
void CornerPolygon(int t, const KnotTracks& meas, const SimInterpolant& interp, const Fit& fit,
                   const std::array<int, 4>& corners, ScoreResult* result) {
  Vector3d pm[4], ps[4];
  bool all_m = true, all_s = true;
  for (int c = 0; c < 4; ++c) {
    const int k = corners[c];
    if (k < 0) {
      all_m = all_s = false;
      continue;
    }
    // A corner left out of the errors (its sigma beyond the bound) leaves the polygon out too.
    const size_t i = static_cast<size_t>(t) * meas.knots() + k;
    all_m = all_m && meas.Valid(t, k) && !(result->compared[i] && !result->informative[i]);
    pm[c] = meas.Position(t, k);
    Vector3d q;
    if (interp.At(meas.time[t] + fit.tau, k, &q, nullptr, nullptr))
      ps[c] = fit.rotation * q + fit.translation;
    else
      all_s = false;
  }
  static constexpr int kPairs[6][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 2}, {1, 3}};
  if (all_m) {
    result->area_measured[t] = QuadArea(pm);
    for (int j = 0; j < 6; ++j)
      result->corner_distance_measured[t][j] = (pm[kPairs[j][0]] - pm[kPairs[j][1]]).norm();
  }
  if (all_s) {
    result->area_simulated[t] = QuadArea(ps);
    for (int j = 0; j < 6; ++j)
      result->corner_distance_simulated[t][j] = (ps[kPairs[j][0]] - ps[kPairs[j][1]]).norm();
  }
}

// Baseline sum d2, with each point's own weight.
double BaselineD2(const KnotTracks& meas, const Scorer& scorer, const Fit& fit,
                  const StraightLineFlight& baseline, const ScoreResult& result) {
  double sum_bd2 = 0;
  for (const Point& pt : scorer.points()) {
    const size_t i = static_cast<size_t>(pt.frame) * meas.knots() + pt.knot;
    if (!result.compared[i] || !baseline.Covers(pt.knot)) continue;
    const Vector3d rb =
        meas.Position(pt.frame, pt.knot) - baseline.At(pt.knot, meas.time[pt.frame]);
    Vector3d r;
    Matrix3d w;
    scorer.Residual(pt, fit, &r, &w, nullptr);
    sum_bd2 += rb.dot(w * rb);
  }
  return sum_bd2;
}

// Stage 2: r and d2 at the fit; the per-frame, per-knot and per-class tables; the sums of the
// test and of the skill's baseline.
ResidualSums CompareAtFit(const ScoreInput& in, const Scorer& scorer,
                          const std::vector<int>& sim_knot, const Fit& fit, ScoreResult* result) {
  const KnotTracks& meas = in.meas;
  const int frames = meas.frames(), knots = meas.knots();
  ResidualSums sums;
  std::vector<Vector3d> sim_pos;  // measured frame
  std::vector<double> sigma;      // each compared point's largest sigma, m
  ResidualsAtFit(meas, scorer, fit, result, &sim_pos, &sums, &sigma);
  MarkInformative(in.options, sigma, result);
  const std::map<int, std::array<int, 2>> extent = NetExtents(meas);
  result->knot_class = KnotClasses(meas, extent);
  const int first_frame = FirstComparedFrame(*result, frames, knots);
  if (first_frame == frames) Fail(NoOverlapMessage(in));
  const StraightLineFlight baseline(scorer.interpolant(), fit, meas.time[first_frame] + fit.tau,
                                    knots);
  const std::array<int, 4> corners = FirstNetCorners(meas, extent);
  result->summary.side_m = FirstRowLength(meas, in.sim, sim_knot, extent);
  StartTables(meas, result);
  for (int t = 0; t < frames; ++t) {
    TabulateFrame(t, meas, sim_pos, baseline, result, &sums);
    CornerPolygon(t, meas, scorer.interpolant(), fit, corners, result);
  }
  sums.baseline_d2 = BaselineD2(meas, scorer, fit, baseline, *result);
  for (auto& row : result->summary.per_class) FinishRow(&row);
  for (auto& row : result->summary.per_knot) FinishRow(&row);
  return sums;
}

// Stage 3's sizes, errors and the test: sum d2 against chi^2, inflated by the correlation in time
// and within a frame; the skill against the baseline.
void ConsistencyTest(const ScoreInput& in, const ResidualSums& sums, int parameters,
                     ScoreResult* result) {
  ScoreSummary& s = result->summary;
  const int frames = in.meas.frames(), knots = in.meas.knots(), p = parameters;
  s.knots = knots;
  for (int t = 0; t < frames; ++t)
    for (int k = 0; k < knots; ++k)
      if (result->compared[static_cast<size_t>(t) * knots + k]) {
        ++s.frames;
        break;
      }
  for (uint8_t c : result->compared) s.points += c;
  if (s.points == 0) Fail(NoOverlapMessage(in));
  const int n = s.points, informative = s.points - s.left_out;
  s.rms_m = informative > 0 ? std::sqrt(sums.e2 / informative) : kNaN;
  s.rms_percent_of_side = s.side_m > 0 ? 100.0 * s.rms_m / s.side_m : kNaN;
  s.weighted_rms_m = sums.weights > 0 ? std::sqrt(sums.weighted_e2 / sums.weights) : kNaN;
  s.mean_d2 = sums.d2 / n;
  s.fitted_parameters = p;
  s.dof = 3.0 * n - p;
  s.tau_int = IntegratedAutocorrelation(result->d2, frames, knots);
  s.design_effect = DesignEffect(result->d2, frames, knots);
  const double inflation = s.tau_int * s.design_effect;
  s.effective_points = n / inflation;
  const double nu_eff = s.dof / inflation;
  s.p_value = UpperGammaQ(nu_eff / 2, sums.d2 / inflation / 2);
  s.critical_mean_d2 = Chi2Quantile(1 - in.options.significance, nu_eff) * inflation / n;
  s.margin = s.critical_mean_d2 - s.mean_d2;
  s.verdict = s.p_value >= in.options.significance ? Verdict::kConsistent : Verdict::kInconsistent;
  s.covariance_too_large =
      1 - UpperGammaQ(nu_eff / 2, sums.d2 / inflation / 2) < in.options.significance;
  s.skill = sums.baseline_d2 > 0 ? 1 - sums.d2 / sums.baseline_d2 : kNaN;
  s.baseline_rms_m =
      sums.baseline_points > 0 ? std::sqrt(sums.baseline_e2 / sums.baseline_points) : kNaN;
}

// The fitted alignment and its uncertainty: the inverse normal matrix, inflated by the
// correlation (fewer independent points) and by the misfit when the model does not explain the
// data.
void SummariseAlignment(const ScoreOptions& options, const FittedAlignment& fitted,
                        ScoreSummary* s) {
  s->time_offset_s = fitted.fit.tau;
  s->rotation = fitted.fit.rotation;
  s->translation = fitted.fit.translation;
  if (fitted.parameters > 0) {
    const double inflation = s->tau_int * s->design_effect;
    const Eigen::MatrixXd cov =
        fitted.normal.inverse() * inflation * std::max(1.0, s->mean_d2 / 3.0);
    int a = 0;
    if (FitsTime(options.alignment)) s->time_offset_sigma_s = std::sqrt(cov(a, a)), ++a;
    if (FitsRigid(options.alignment)) s->rigid_covariance = cov.block(a, a, 6, 6);
  }
}

// The simulation's sampling: is cubic interpolation good enough against the measurement?
void CheckSampling(const ScoreOptions& options, const ResidualSums& sums, ScoreSummary* s) {
  const int n = s->points;
  s->interpolation_rms_m = std::sqrt(sums.interp_sq / n);
  const double meas_rms_sigma = std::sqrt(sums.meas_var / n);
  s->sim_too_sparse = s->interpolation_rms_m > options.max_interpolation_fraction * meas_rms_sigma;
  if (s->sim_too_sparse) {
    std::ostringstream o;
    o << "simulation output too sparse: frames every " << s->sim_interval_s * 1e3
      << " ms interpolate to " << s->interpolation_rms_m * 1e3 << " mm RMS, more than "
      << options.max_interpolation_fraction * 100 << " % of the measurement's "
      << meas_rms_sigma * 1e3 << " mm; write the simulation at a smaller output_interval "
      << "(the interpolation error is added to Sigma_sim)";
    s->notes.push_back(o.str());
  }
  if (s->sim_interval_s > s->meas_interval_s * 1.0001 && s->meas_interval_s > 0) {
    std::ostringstream o;
    o << "the simulation is stored every " << s->sim_interval_s * 1e3 << " ms, sparser than the "
      << "measurement (" << s->meas_interval_s * 1e3 << " ms)";
    s->notes.push_back(o.str());
  }
}

// Where Sigma_sim and Sigma_meas come from, and whether the test finds them too large.
void DescribeUncertainties(const ScoreInput& in, ScoreSummary* s) {
  const ScoreOptions& options = in.options;
  if (!in.sim.covariance.empty()) {
    s->sim_uncertainty = "from " + in.sim_name + " /knots/covariance";
  } else if (options.sim_sigma_m > 0) {
    std::ostringstream o;
    o << "isotropic " << options.sim_sigma_m * 1e3 << " mm";
    s->sim_uncertainty = o.str();
  } else {
    s->sim_uncertainty = "zero";
    s->notes.push_back(
        "Sigma_sim is zero (no discretisation study given): d2 weighs the "
        "measurement's covariance only");
  }
  if (in.meas.covariance.empty()) {
    std::ostringstream o;
    o << in.meas_name << " has no /knots/covariance: isotropic " << options.meas_sigma_m * 1e3
      << " mm used";
    s->notes.push_back(o.str());
  }
  if (s->covariance_too_large && s->mean_d2 > 0 && s->points > 0) {
    // What the stated uncertainty exceeds the scatter by, in standard deviation.
    std::ostringstream o;
    o << "mean d2 is below its expectation beyond chance: the stated covariances are larger than "
      << "the scatter (by about "
      << std::lround(100 * (std::sqrt(s->dof / s->points / s->mean_d2) - 1))
      << " % in standard deviation)";
    s->notes.push_back(o.str());
  }
}

// The largest corner-polygon areas, measured and simulated, and when, into the summary. Returns
// the frame of the simulated one; -1 when no frame has all four corners simulated.
int LargestAreas(const KnotTracks& meas, ScoreResult* result) {
  ScoreSummary& s = result->summary;
  double max_area = -1;
  int max_t = -1;
  for (int t = 0; t < meas.frames(); ++t) {
    if (std::isfinite(result->area_simulated[t]) && result->area_simulated[t] > max_area)
      max_area = result->area_simulated[t], max_t = t;
    if (std::isfinite(result->area_measured[t]) &&
        result->area_measured[t] > s.max_area_measured_m2)
      s.max_area_measured_m2 = result->area_measured[t], s.max_area_time_measured_s = meas.time[t];
  }
  if (s.max_area_measured_m2 <= 0)  // no frame with all four corners measured
    s.max_area_measured_m2 = s.max_area_time_measured_s = kNaN;
  if (max_t >= 0) {
    s.max_area_simulated_m2 = max_area;
    s.max_area_time_simulated_s = meas.time[max_t];
  }
  return max_t;
}

// A phase's name and measured time span [start, end), s.
using PhaseSpan = std::tuple<const char*, double, double>;

// The phases' spans from the simulated area's largest frame max_t (see LargestAreas) and the
// contact time (simulated, so shifted by the offset tau).
std::array<PhaseSpan, 4> PhaseSpans(const KnotTracks& meas, const ScoreResult& result, int max_t,
                                    double tau) {
  const ScoreSummary& s = result.summary;
  const double t_end = meas.time.back() + 1e-9;
  double t_half = meas.time.front(), t_max = t_end;
  if (max_t >= 0) {
    t_max = meas.time[max_t];
    for (int t = 0; t <= max_t; ++t)
      if (result.area_simulated[t] >= 0.5 * s.max_area_simulated_m2) {
        t_half = meas.time[t];
        break;
      }
  }
  const double t_contact = std::isfinite(s.contact_time_s)
                               ? std::clamp(s.contact_time_s - tau, meas.time.front(), t_end)
                               : t_end;
  t_max = std::min(t_max, t_contact);
  t_half = std::min(t_half, t_max);
  return {{{"ejection", meas.time.front(), t_half},
           {"spreading", t_half, t_max},
           {"opened", t_max, t_contact},
           {"contact", t_contact, t_end}}};
}

// The table row of the knot-frames compared in the measured time span [lo, hi).
ScoreRow PhaseRow(const PhaseSpan& span, const KnotTracks& meas, const ScoreResult& result) {
  const auto& [name, lo, hi] = span;
  const int knots = meas.knots();
  ScoreRow row;
  row.name = name;
  row.start_s = lo;
  row.end_s = hi;
  for (int t = 0; t < meas.frames(); ++t) {
    if (meas.time[t] < lo || meas.time[t] >= hi) continue;
    for (int k = 0; k < knots; ++k) {
      const size_t i = static_cast<size_t>(t) * knots + k;
      if (!result.compared[i]) continue;
      AddRow(&row, result.residual[i].squaredNorm(), result.d2[i], result.informative[i]);
      row.sigma_sim_m += result.sim_var[i];
      row.sigma_meas_m += result.meas_var[i];
    }
  }
  row.sigma_sim_m = row.points > 0 ? std::sqrt(row.sigma_sim_m / row.points) : kNaN;
  row.sigma_meas_m = row.points > 0 ? std::sqrt(row.sigma_meas_m / row.points) : kNaN;
  FinishRow(&row);
  return row;
}

// The headline: the errors, over how many points, how many were left out and why, in one
// sentence; the covariance-weighted RMS beside it when the sigmas differ strongly.
std::string Headline(const ScoreSummary& s) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  auto mm = [](double m) {
    std::ostringstream v;
    v.setf(std::ios::fixed);
    const double x = m * 1e3;
    v.precision(x >= 100 ? 0 : x >= 10 ? 1 : x >= 1 ? 2 : 3);
    v << x << " mm";
    return v.str();
  };
  const int informative = s.points - s.left_out;
  o << "RMS " << mm(s.rms_m) << " and largest " << mm(s.max_m) << " over ";
  if (s.left_out == 0) {
    o << "all " << s.points << " compared knot-frames (every sigma within " << mm(s.sigma_bound_m)
      << ")";
  } else {
    o << informative << " of the " << s.points << " compared knot-frames; " << s.left_out
      << " left out of both because their own sigma (up to " << mm(s.left_out_max_sigma_m)
      << ") exceeds " << mm(s.sigma_bound_m) << " (" << s.sigma_bound_from
      << "): they count in d2 only";
  }
  if (s.degenerate > 0)
    o << "; " << s.degenerate << (s.left_out > 0 ? " more" : "")
      << " flagged degenerate by the triangulation (rays nearly parallel or head-on) are not "
         "compared";
  if (s.left_out > 0 || s.sigma_spread > 2.0)
    o << "; covariance-weighted RMS " << mm(s.weighted_rms_m);
  o << ".";
  return o.str();
}

// Stage 4: where the contact phase starts, and the per-phase table.
void ScorePhases(const ScoreInput& in, double tau, ScoreResult* result) {
  ScoreSummary& s = result->summary;
  const int max_t = LargestAreas(in.meas, result);
  // The contact phase from the given time, else from the simulation's own first contact.
  s.contact_time_s =
      std::isfinite(in.options.contact_time_s) ? in.options.contact_time_s : in.sim.contact_start_s;
  s.contact_from = std::isfinite(in.options.contact_time_s) ? ContactFrom::kGiven
                   : std::isfinite(in.sim.contact_start_s)  ? ContactFrom::kSimulation
                                                            : ContactFrom::kNone;
  for (const PhaseSpan& span : PhaseSpans(in.meas, *result, max_t, tau))
    s.per_phase.push_back(PhaseRow(span, in.meas, *result));
}

// Stage 5: counts of the compared d2 and their expectation under chi^2_3.
void D2Histogram(ScoreResult* result) {
  constexpr int kBins = 30;
  constexpr double kWidth = 0.5;
  const int n = result->summary.points;
  result->d2_counts.assign(kBins, 0);
  result->d2_expected.assign(kBins, 0);
  for (int b = 0; b <= kBins; ++b) result->d2_edges.push_back(b * kWidth);
  for (size_t i = 0; i < result->compared.size(); ++i)
    if (result->compared[i])
      // In double first: a d2 of 1e10 (a wrong model) would overflow an int.
      result->d2_counts[static_cast<int>(std::clamp(result->d2[i] / kWidth, 0.0, kBins - 1.0))]++;
  for (int b = 0; b < kBins; ++b) {
    const double upper = b == kBins - 1 ? 0.0 : UpperGammaQ(1.5, result->d2_edges[b + 1] / 2);
    result->d2_expected[b] = n * (UpperGammaQ(1.5, result->d2_edges[b] / 2) - upper);
  }
}

}  // namespace

Comparison PrepareComparison(const KnotTracks& meas, const KnotTracks& sim,
                             const ScoreOptions& options, const std::string& meas_name,
                             const std::string& sim_name) {
  const ScoreInput in{meas, sim, options, meas_name, sim_name};
  CheckInput(in);
  Comparison c;
  c.sim_knot = MatchKnots(in);
  CheckSimulationFinite(in);
  c.points = MeasuredPoints(in, &c.masked);
  return c;
}

ScoreResult Score(const KnotTracks& meas, const KnotTracks& sim, const ScoreOptions& options,
                  const std::string& meas_name, const std::string& sim_name) {
  const auto start = std::chrono::steady_clock::now();
  const ScoreInput in{meas, sim, options, meas_name, sim_name};
  Comparison c = PrepareComparison(meas, sim, options, meas_name, sim_name);
  const std::vector<int>& sim_knot = c.sim_knot;
  ScoreResult result;
  ScoreSummary& s = result.summary;
  s.masked = c.masked;
  for (uint8_t d : meas.degenerate) s.degenerate += d != 0;
  Scorer scorer(meas, sim, sim_knot, std::move(c.points), options);
  StartSummary(in, &s);

  // 1. The time offset: a coarse search over the window (every point of a thinned set; with a
  // rigid fit, the best rigid motion at each candidate), then Gauss-Newton on all parameters.
  const FittedAlignment fitted = FitAlignment(in, s, &scorer);

  // 2. Residuals and d2 at the fit; the per-frame and per-knot tables.
  const ResidualSums sums = CompareAtFit(in, scorer, sim_knot, fitted.fit, &result);

  // 3. Sizes, errors, the test; the alignment's uncertainty; the sampling and the uncertainties'
  // sources, with a note for each thing a reader must know.
  ConsistencyTest(in, sums, fitted.parameters, &result);
  SummariseAlignment(options, fitted, &s);
  CheckSampling(options, sums, &s);
  DescribeUncertainties(in, &s);
  s.headline = Headline(s);

  // 4. Phases, from the simulated corner-polygon area: ejection until it first reaches half its
  // maximum, spreading until the maximum opening, opened after it, contact from contact_time_s.
  ScorePhases(in, fitted.fit.tau, &result);

  // 5. The d2 histogram against chi^2_3 (bins of 0.5 up to 15, the last one open).
  D2Histogram(&result);

  s.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

// The text summary's layout: its words, and the fields' values and labels by key.
constexpr char kBriefText[] =
    "score: {points} knot-frames ({frames} frames x {knots} knots, {masked} masked), "
    "[alignment]\n"
    "  {headline}\n"
    "  [rms_percent_of_side] % of the {side_m} m side; [per_class.corner] / {per_class.edge} / "
    "{per_class.inner} mm\n"
    "  [time_offset_s@ms] [time_offset_sigma_s@ms] ms; [sim_uncertainty]\n"
    "  [mean_d2] (expected 3; [dof], [effective_points], [tau_int] frames, [design_effect]), "
    "[p_value]\n"
    "  [verdict] with the measurement uncertainty ([critical_mean_d2], [margin]); [skill] "
    "against straight-line flight ({baseline_rms_mm} mm RMS)\n"
    "  [notes]\n";

std::string ScoreSummary::BriefReport() const { return FillSummaryText(kBriefText, *this); }

}  // namespace netlab::netsim
