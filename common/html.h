#pragma once
// The pieces every netlab HTML report writes the same way: numbers for text and SVG, escaped text,
// round axis ticks, a table row. The score's and the sweep's reports use them.

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace netlab::html {

// A number with `digits` significant digits; "nan" when not finite (SVG data attributes).
inline std::string Num(double v, int digits = 9) {
  if (!std::isfinite(v)) return "nan";
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.*g", digits, v);
  return buffer;
}

// A number with `decimals` decimals; "–" when not finite (tables).
inline std::string Fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "–";
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, v);
  return buffer;
}

// Text with <, >, & and " escaped, for element text and attribute values.
inline std::string Escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// Round tick steps: 1, 2 or 5 times a power of ten, about `count` ticks over [lo, hi].
inline std::vector<double> Ticks(double lo, double hi, int count = 5) {
  const double raw = (hi - lo) / count;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  const double step = raw / power < 1.5 ? power : raw / power < 3.5 ? 2 * power : 5 * power;
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * step; t += step)
    ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  return ticks;
}

// One table row of already escaped cells.
inline std::string Row(const std::vector<std::string>& cells, const char* tag = "td") {
  std::string s = "<tr>";
  for (const auto& c : cells) s += std::string("<") + tag + ">" + c + "</" + tag + ">";
  return s + "</tr>\n";
}

}  // namespace netlab::html
