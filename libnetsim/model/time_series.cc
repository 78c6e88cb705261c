#include "libnetsim/model/time_series.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace netlab::netsim {
namespace {

// Parses up to `n` numbers separated by commas and/or whitespace; false if a field is not a number.
bool ParseNumbers(const std::string& line, std::vector<double>* out) {
  std::string text = line;
  std::replace(text.begin(), text.end(), ',', ' ');
  std::istringstream is(text);
  std::string field;
  out->clear();
  while (is >> field) {
    size_t used = 0;
    double value;
    try {
      value = std::stod(field, &used);
    } catch (const std::exception&) {
      return false;
    }
    if (used != field.size()) return false;
    out->push_back(value);
  }
  return true;
}

}  // namespace

TimeSeries3::TimeSeries3(std::vector<double> times, std::vector<Eigen::Vector3d> values)
    : times_(std::move(times)), values_(std::move(values)) {
  if (times_.empty() || times_.size() != values_.size())
    throw std::invalid_argument("time series: needs at least one sample and one value per time");
  for (size_t i = 1; i < times_.size(); ++i)
    if (!(times_[i] > times_[i - 1]))
      throw std::invalid_argument("time series: times must increase strictly");
}

TimeSeries3 TimeSeries3::ReadCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open time series file");
  std::vector<double> times;
  std::vector<Eigen::Vector3d> values;
  std::string line;
  std::vector<double> numbers;
  int line_number = 0;
  bool first_content = true;
  while (std::getline(in, line)) {
    ++line_number;
    const size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    const bool parsed = ParseNumbers(line, &numbers);
    if (!parsed && first_content) {  // header
      first_content = false;
      continue;
    }
    first_content = false;
    auto where = [&] { return path + ":" + std::to_string(line_number) + ": "; };
    if (!parsed || numbers.size() != 4)
      throw std::runtime_error(where() + "expected 4 numbers 't,x,y,z', got '" + line + "'");
    for (double v : numbers)
      if (!std::isfinite(v)) throw std::runtime_error(where() + "value is not finite");
    if (!times.empty() && !(numbers[0] > times.back()))
      throw std::runtime_error(where() + "time " + std::to_string(numbers[0]) +
                               " does not increase (previous " + std::to_string(times.back()) +
                               ")");
    times.push_back(numbers[0]);
    values.emplace_back(numbers[1], numbers[2], numbers[3]);
  }
  if (times.empty()) throw std::runtime_error(path + ": no samples in time series file");
  return TimeSeries3(std::move(times), std::move(values));
}

size_t TimeSeries3::Interval(double t) const {
  if (times_.size() < 2) return 0;
  const auto it = std::upper_bound(times_.begin(), times_.end(), t);
  const size_t i = it == times_.begin() ? 0 : static_cast<size_t>(it - times_.begin()) - 1;
  return std::min(i, times_.size() - 2);
}

Eigen::Vector3d TimeSeries3::Value(double t) const {
  if (times_.size() == 1 || t <= times_.front()) return values_.front();
  if (t >= times_.back()) return values_.back();
  const size_t i = Interval(t);
  const double a = (t - times_[i]) / (times_[i + 1] - times_[i]);
  return (1.0 - a) * values_[i] + a * values_[i + 1];
}

Eigen::Vector3d TimeSeries3::Rate(double t) const {
  if (times_.size() < 2 || t < times_.front() || t >= times_.back()) return Eigen::Vector3d::Zero();
  const size_t i = Interval(t);
  return (values_[i + 1] - values_[i]) / (times_[i + 1] - times_[i]);
}

}  // namespace netlab::netsim
