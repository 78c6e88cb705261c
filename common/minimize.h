#pragma once
// One-dimensional minimisation shared by the fits that search a single parameter.

#include <cmath>

namespace netlab {

// Golden-section search for the minimum of f on [a, b], to an interval of `tolerance`; f is
// assumed unimodal there (bracket it first, e.g. by a coarse grid).
template <typename F>
double GoldenSection(F f, double a, double b, double tolerance) {
  const double r = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = b - r * (b - a), d = a + r * (b - a), fc = f(c), fd = f(d);
  while (b - a > tolerance) {
    if (fc < fd) {
      b = d, d = c, fd = fc, c = b - r * (b - a), fc = f(c);
    } else {
      a = c, c = d, fc = fd, d = a + r * (b - a), fd = f(d);
    }
  }
  return 0.5 * (a + b);
}

}  // namespace netlab
