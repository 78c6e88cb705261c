#pragma once
// A vector-valued time series read from CSV (t, x, y, z per line), linearly interpolated.
// Used for measured gravity (accelerometer) and angular velocity (gyro) during a parabola.
//
// File format: one sample per line, "t,x,y,z" (commas or whitespace), t in seconds strictly
// increasing; blank lines and lines starting with '#' are skipped; a first line that does not
// parse as numbers is taken as a header. Outside [t_first, t_last] the end values hold.

#include <Eigen/Core>
#include <string>
#include <vector>

namespace netlab::netsim {

class TimeSeries3 {
 public:
  TimeSeries3() = default;
  TimeSeries3(std::vector<double> times, std::vector<Eigen::Vector3d> values);

  // Reads a CSV file. Throws std::runtime_error naming the file and line on bad input.
  static TimeSeries3 ReadCsv(const std::string& path);

  Eigen::Vector3d Value(double t) const;
  // d/dt of the interpolant (piecewise constant; 0 outside the samples), units/s.
  Eigen::Vector3d Rate(double t) const;

  bool empty() const { return times_.empty(); }
  double first_time() const { return times_.front(); }
  double last_time() const { return times_.back(); }
  size_t size() const { return times_.size(); }

 private:
  // Index i with times_[i] <= t < times_[i+1], clamped to [0, n-2].
  size_t Interval(double t) const;

  std::vector<double> times_;
  std::vector<Eigen::Vector3d> values_;
};

}  // namespace netlab::netsim
