#pragma once
// The pieces every netlab HTML report writes the same way: numbers for text and SVG, escaped text,
// round axis ticks, a plot's axes, a table row. The score's and the sweep's reports use them.

#include <cmath>
#include <cstdio>
#include <functional>
#include <ostream>
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
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
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

// A plot's box in its SVG (px): the SVG's size and the margins around the plotting area.
struct PlotFrame {
  double width = 560, height = 300, left = 62, right = 14, top = 30, bottom = 44;
  double y_label_x = 16;  // where the rotated y label's centre line lies
  double X(double x, double x0, double x1) const {
    return left + (x - x0) / (x1 - x0) * (width - left - right);
  }
  double Y(double y, double y0, double y1) const {
    return height - bottom - (y - y0) / (y1 - y0) * (height - top - bottom);
  }
};

// The axes of a plot over [x0, x1] x [y0, y1] as one SVG group: a grid line and a label per tick
// (`tick_text` writes them), the plotting area's frame, and the axis labels (escaped here).
inline void PlotAxes(std::ostream& o, const PlotFrame& f, double x0, double x1, double y0,
                     double y1, const std::vector<double>& x_ticks,
                     const std::vector<double>& y_ticks,
                     const std::function<std::string(double)>& x_tick_text,
                     const std::function<std::string(double)>& y_tick_text,
                     const std::string& x_label, const std::string& y_label) {
  o << "<g class=\"axes\">\n";
  for (double t : y_ticks) {
    const double y = f.Y(t, y0, y1);
    o << "<line x1=\"" << f.left << "\" x2=\"" << f.width - f.right << "\" y1=\"" << Fixed(y, 1)
      << "\" y2=\"" << Fixed(y, 1) << "\" class=\"grid\"/><text x=\"" << f.left - 6 << "\" y=\""
      << Fixed(y + 4, 1) << "\" text-anchor=\"end\">" << y_tick_text(t) << "</text>\n";
  }
  for (double t : x_ticks) {
    const double x = f.X(t, x0, x1);
    o << "<line y1=\"" << f.top << "\" y2=\"" << f.height - f.bottom << "\" x1=\"" << Fixed(x, 1)
      << "\" x2=\"" << Fixed(x, 1) << "\" class=\"grid\"/><text x=\"" << Fixed(x, 1) << "\" y=\""
      << f.height - f.bottom + 16 << "\" text-anchor=\"middle\">" << x_tick_text(t) << "</text>\n";
  }
  o << "<rect x=\"" << f.left << "\" y=\"" << f.top << "\" width=\"" << f.width - f.left - f.right
    << "\" height=\"" << f.height - f.top - f.bottom << "\" class=\"frame\"/>\n";
  o << "<text x=\"" << (f.left + f.width - f.right) / 2 << "\" y=\"" << f.height - 8
    << "\" text-anchor=\"middle\" class=\"label\">" << Escape(x_label) << "</text>\n";
  o << "<text transform=\"translate(" << f.y_label_x << "," << (f.top + f.height - f.bottom) / 2
    << ") rotate(-90)\" text-anchor=\"middle\" class=\"label\">" << Escape(y_label)
    << "</text>\n</g>\n";
}

// One table row of already escaped cells.
inline std::string Row(const std::vector<std::string>& cells, const char* tag = "td") {
  std::string s = "<tr>";
  for (const auto& c : cells) s += std::string("<") + tag + ">" + c + "</" + tag + ">";
  return s + "</tr>\n";
}

}  // namespace netlab::html
